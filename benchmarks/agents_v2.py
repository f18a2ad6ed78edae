"""Goal-conditioned agents on procedural-v2, next to the planner: docs/results/agents_v2.*.

Trains the goal-conditioned slot policy (`utamp_gym.rl.slots`: the goal entries of
``UTampKitchenGoals-v0``'s observation read per slot and per pair) on ``procedural-v2/train``
with `utamp train`'s functions, one row per learner, several seeds:

* BC: behaviour cloning from planner episodes (``utamp2x-rules``, the planner the v2 labels
  assume, recorded with `utamp demos`' recorder on the training split, reset seeds from
  100,000; only episodes that reach the goal are cloned);
* MaskablePPO from scratch and BC then MaskablePPO (``ft``: from the BC model of the same
  seed), each seed stopped at the first evaluation where its curve on the training split is
  flat (``--plateau``: `utamp_gym.rl.callbacks.plateaued`, at least 10 evaluations), at
  ``--ppo-steps`` / ``--ft-steps``, or at its first evaluation after ``--time-limit`` /
  ``--ft-time-limit`` seconds of training (the steps reached are recorded). Evaluations
  during training: ``--eval-episodes`` fixed episodes of the training split (its first
  scenes in turn), every ``--eval-every`` steps.

The env: ``UTampKitchenGoals-v0`` with 8 object slots (``slots=8``: one policy for every split,
test-count's 8-object scenes included, smaller scenes padded), the extended domain with
rule-derived affordances (``domain="utamp2x"``, ``affordances="rules"``: the planner's view;
masks: the U-TAMP-2 precondition under those affordances), symbolic grounding, shaped reward.
Each seed's final model is evaluated with `utamp eval`'s sweep (``rl:PATH``, deterministic
masked policy, 10 steps per object) on every scene of every v2 split (``--limit``: the first
N scenes of each), and the planner (``utamp2x-rules``) by the same sweep: its plans played in
the env of the utamp2x domain and checked against its ground truth, as `utamp eval` does.
Writes

* ``docs/results/agents_v2.md``: rows x splits, success mean ± 95 % t interval over the
  seeds, the train → test-tasks gap (per seed, then its interval), the achievable share of
  the evaluated scenes (the ceiling), budgets, steps and wall time per seed;
* ``docs/results/agents_v2.json``: every number (per seed and split, pooled Wilson intervals);
* ``docs/results/agents_v2_curves.png``: the learning curves (success on the training split).

    python benchmarks/agents_v2.py [--seeds 3] [--demos 1200] [--bc-epochs 30]
        [--ppo-steps 200000] [--time-limit S] [--ft-steps N] [--ft-time-limit S]
        [--plateau 0.02] [--rows bc,ppo,ft] [--envs 8] [--eval-every N] [--eval-episodes N]
        [--limit N] [--workers N] [--train-workers N] [--train-only] [--out runs/agents_v2]
        [--docs docs/results] [--rewrite]

Runs resume: with the same ``--out``, the demonstrations, every finished seed of the same
configuration and every evaluated (scene, method) row are reused, so the same command
continues an interrupted run.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from agents import evaluate_all, fine_tune, flat_curve, load  # benchmarks/ is on sys.path when run

from utamp_gym.distributed import make_executor
from utamp_gym.eval.intervals import t_interval, wilson_interval
from utamp_gym.provenance import commit, write_json, write_markdown
from utamp_gym.rl.callbacks import plot_learning_curves

ENV_ID = "UTampKitchenGoals-v0"
#: the agents' env options beyond the env id's (saved with each model, so `utamp eval`
#: rebuilds the same env on every split)
ENV_OPTIONS = {"slots": 8, "domain": "utamp2x", "affordances": "rules"}
MASKS = "affordances"
PLANNER = "utamp2x-rules"
ROWS = {"bc": "BC from planner episodes", "ppo": "MaskablePPO from scratch",
        "ft": "BC, then MaskablePPO"}  # fmt: skip
#: the split the train → test gap is measured to (held-out templates and compositions)
HELD_OUT = "test-tasks"


def split_suites(hard: bool = False) -> dict[str, str]:
    """Split name -> suite: procedural-v2's splits (``hard`` only if asked)."""
    from utamp_gym.suites.procedural_v2 import SPLITS, SUITE

    return {s: f"{SUITE}/{s}" for s in SPLITS if hard or s != "hard"}


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--demos", type=int, default=1_200,
                   help="planner episodes for BC (random training scenes by reset seed: 1,200 "
                   "draws meet about 95 %% of the 400)")  # fmt: skip
    p.add_argument("--bc-epochs", type=int, default=30)
    p.add_argument("--ppo-steps", type=int, default=200_000)
    p.add_argument("--ft-steps", type=int, default=200_000)
    p.add_argument("--time-limit", type=float, default=None,
                   help="stop a MaskablePPO seed at its first evaluation after this many "
                   "training seconds")  # fmt: skip
    p.add_argument("--ft-time-limit", type=float, default=None,
                   help="the same for fine-tuning (default: --time-limit)")  # fmt: skip
    p.add_argument("--plateau", type=float, default=0.02,
                   help="stop a MaskablePPO seed once its curve gained less than this over its "
                   "last 20 %% (0: never)")  # fmt: skip
    p.add_argument("--envs", type=int, default=8, help="MaskablePPO's parallel envs")
    p.add_argument("--rows", default="bc,ppo,ft", help=f"learned rows: any of {', '.join(ROWS)}")
    p.add_argument("--eval-every", type=int, default=4_096)
    p.add_argument("--eval-episodes", type=int, default=20,
                   help="evaluation episodes of the training split during training")  # fmt: skip
    p.add_argument("--limit", type=int, default=None, help="scenes per split (first N)")
    p.add_argument("--hard", action="store_true", help="also evaluate procedural-v2/hard")
    p.add_argument("--workers", type=int, default=0,
                   help="evaluation worker processes (0: in this process)")  # fmt: skip
    p.add_argument("--train-workers", type=int, default=0,
                   help="train a row's seeds in this many worker processes (0: one after "
                   "another in this process)")  # fmt: skip
    p.add_argument("--out", default="runs/agents_v2")
    p.add_argument("--docs", default="docs/results")
    p.add_argument("--train-only", action="store_true",
                   help="train (or reuse) the rows and stop: processes can train rows at once, "
                   "a later run evaluates them")  # fmt: skip
    p.add_argument("--rewrite", action="store_true",
                   help="only rewrite the docs from the measured agents_v2.json")  # fmt: skip
    return p


def record_or_reuse_demos(suite: str, episodes: int, root: Path) -> dict[str, Any]:
    """`episodes` planner (`PLANNER`) episodes of `suite` in the agents' env (reset seeds from
    100,000, symbolic grounding), or the ones already under `root`."""
    from utamp_gym.data.record import record_demos

    marker = root / "demos.json"
    want = {"suite": suite, "requested": episodes, "seed": 100_000, "method": PLANNER,
            "env_options": ENV_OPTIONS}  # fmt: skip
    if marker.is_file():
        done = json.loads(marker.read_text())
        if {k: done.get(k) for k in want} == want and Path(done["path"]).is_dir():
            return done
    options = {"grounding": "symbolic", "interface": "objects", "masks": MASKS, **ENV_OPTIONS}
    demo = record_demos(suite, episodes, root, seed=100_000, method=PLANNER, env_options=options)
    done = {**want, "path": str(demo.path), "episodes": demo.episodes, "steps": demo.steps,
            "successes": demo.successes,
            "left_out": {**demo.failed, **demo.unsolvable}}  # fmt: skip
    marker.write_text(json.dumps(done, indent=2) + "\n")
    return done


def train_rows(args: argparse.Namespace, out: Path, train_suite: str) -> dict[str, Any]:
    """Row label -> {"runs": seed run folders, "demos": ...}: the learned rows, trained (or
    reused)."""
    from utamp_gym.rl.seeds import train_seeds

    rows = [r.strip() for r in args.rows.split(",") if r.strip()]
    unknown = [r for r in rows if r not in ROWS]
    if unknown:
        raise SystemExit(f"--rows: unknown {unknown}; valid: {', '.join(ROWS)}")
    common = {"env_id": ENV_ID, "masks": MASKS, "interface": "objects",
              "eval_episodes": args.eval_episodes, "progress": False,
              "env_options": dict(ENV_OPTIONS)}  # fmt: skip
    rl = {"n_envs": args.envs, "eval_every": args.eval_every,
          "stop_at_plateau": args.plateau or None}  # fmt: skip
    executor = make_executor("local", workers=args.train_workers) if args.train_workers else None
    done: dict[str, Any] = {}
    if "bc" in rows or "ft" in rows:
        demo = record_or_reuse_demos(train_suite, args.demos, out / "demos")
        agg = train_seeds(args.seeds, out=out / "bc", algo="bc", demos=demo["path"],
                          hyperparams={"epochs": args.bc_epochs}, executor=executor,
                          **common)  # fmt: skip
        done["bc"] = {"runs": agg["runs"], "demos": demo}
    if "ppo" in rows:
        agg = train_seeds(args.seeds, out=out / "ppo", algo="maskable-ppo",
                          steps=args.ppo_steps, time_limit_s=args.time_limit, executor=executor,
                          **rl, **common)  # fmt: skip
        done["ppo"] = {"runs": agg["runs"]}
    if "ft" in rows:
        limit = args.time_limit if args.ft_time_limit is None else args.ft_time_limit
        ft = {"algo": "maskable-ppo", "steps": args.ft_steps, "time_limit_s": limit,
              **rl, **common}  # fmt: skip
        tuned = fine_tune(args.seeds, out, ft, executor)
        done["ft"] = {"runs": [r for a in tuned for r in a["runs"]]}
    return {k: v for k, v in done.items() if k in rows}


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    docs = Path(args.docs)
    if args.rewrite:
        write(json.loads((docs / "agents_v2.json").read_text()), docs)
        return
    out = Path(args.out)
    suites = split_suites(args.hard)
    load_at_start = load()
    start = time.perf_counter()
    trained = train_rows(args, out, suites["train"])
    if args.train_only:
        return
    train_wall = time.perf_counter() - start
    table: dict[str, Any] = {"env_id": ENV_ID, "env_options": ENV_OPTIONS, "masks": MASKS,
                             "splits": suites, "limit": args.limit, "methods": {},
                             "planner": PLANNER}  # fmt: skip
    if "bc" in trained:
        d = trained["bc"]["demos"]
        table["demos"] = {k: d[k] for k in ("episodes", "steps", "successes", "method")}
        table["demos"]["left_out"] = len(d.get("left_out", {}))
    models = [f"rl:{Path(run) / 'model.zip'}" for row in trained.values() for run in row["runs"]]
    evaluated = {split: evaluate_all((*models, PLANNER), suite, out / "eval", args.workers,
                                     args.limit) for split, suite in suites.items()}  # fmt: skip
    for key, row in trained.items():
        per_seed = []
        for run in map(Path, row["runs"]):
            report = json.loads((run / "train.json").read_text())
            method = f"rl:{run / 'model.zip'}"
            success = {split: _rates(evaluated[split][method]) for split in suites}
            per_seed.append({"run": str(run), "seed": report["config"]["seed"],
                             "steps": report["steps"], "wall_time_s": report["wall_time_s"],
                             "train_time_s": report["train_time_s"], "curve": report["curve"],
                             "config": report["config"], "success": success})  # fmt: skip
        table["methods"][ROWS[key]] = {"kind": "learned", "per_seed": per_seed}
    success = {split: _rates(evaluated[split][PLANNER]) for split in suites}
    table["methods"][f"planner ({PLANNER})"] = {"kind": "planner", "success": success}
    table["achievable"] = achievable(suites, args.limit)
    table["load_average"] = {"start": load_at_start, "end": load()}
    table["training_wall_time_s"] = round(train_wall, 1)
    table["total_wall_time_s"] = round(time.perf_counter() - start, 1)
    write(table, docs)


def _rates(rows: list[Any]) -> dict[str, Any]:
    k = sum(r.success for r in rows)
    return {"rate": k / len(rows), "n": len(rows), "successes": k}


def achievable(suites: dict[str, str], limit: int | None) -> dict[str, list[int]]:
    """Per split: [evaluated scenes whose goal is labelled achievable, evaluated scenes]."""
    from utamp_gym.suites.procedural_v2 import split_scenes

    out = {}
    for split in suites:
        scenes = split_scenes(split)[:limit]
        out[split] = [sum(s.achievable for s in scenes), len(scenes)]
    return out


def summarise(m: dict[str, Any], splits: list[str]) -> dict[str, Any]:
    """A learned row's per-split mean, t interval and pooled Wilson interval, and its train →
    `HELD_OUT` gap (per seed, then the t interval of the per-seed gaps)."""
    seeds = m["per_seed"]
    summary: dict[str, Any] = {}
    for s in splits:
        mean, half = t_interval([p["success"][s]["rate"] for p in seeds])
        k = sum(p["success"][s]["successes"] for p in seeds)
        n = sum(p["success"][s]["n"] for p in seeds)
        summary[s] = {"mean": mean, "t95_half_width": half,
                      "pooled_wilson95": wilson_interval(k, n)}  # fmt: skip
    if HELD_OUT in splits:
        gaps = [p["success"]["train"]["rate"] - p["success"][HELD_OUT]["rate"] for p in seeds]
        mean, half = t_interval(gaps)
        summary["gap"] = {"mean": mean, "t95_half_width": half}
    return summary


def write(table: dict[str, Any], docs: Path) -> None:
    """agents_v2.json and agents_v2.md from the measured table."""
    docs.mkdir(parents=True, exist_ok=True)
    splits = list(table["splits"])
    ceiling = table["achievable"]
    scope = "all its scenes" if table.get("limit") is None else f"its first {table['limit']} scenes"
    lines = [
        f"Training split: `{table['splits']['train']}` ({table['env_id']}, objects interface with "
        f"8 slots and the goal entries, domain utamp2x with rule-derived affordances, masks: "
        f"the U-TAMP-2 precondition under them, symbolic grounding); every split evaluated on "
        f"{scope}, seed 0, symbolic grounding, deterministic masked policy, 10 steps per "
        "object. Learned rows: mean over seeds ± 95 % t interval (pooled Wilson intervals in "
        f"the JSON); gap: train − {HELD_OUT} per seed, mean ± its t interval. Planner row: one "
        "deterministic run per scene.",
        "",
        "| method | seeds | "
        + " | ".join(f"{s} ({ceiling[s][0]}/{ceiling[s][1]} achievable)" for s in splits)
        + f" | gap train → {HELD_OUT} | steps / seed | wall s / seed | curve flat / seed |",
        "|---" * (len(splits) + 6) + "|",
    ]
    for label, m in table["methods"].items():
        if m["kind"] == "planner":
            cells = [f"{m['success'][s]['rate']:.2f} (n={m['success'][s]['n']})" for s in splits]
            gap = m["success"]["train"]["rate"] - m["success"][HELD_OUT]["rate"]
            lines.append(f"| {label} | – | " + " | ".join(cells) + f" | {gap:+.2f} | – | – | – |")
            continue
        summary = m["summary"] = summarise(m, splits)
        seeds = m["per_seed"]
        cells = [f"{summary[s]['mean']:.2f} ± {summary[s]['t95_half_width']:.2f}" for s in splits]
        gap = summary["gap"]
        lines.append(
            f"| {label} | {len(seeds)} | " + " | ".join(cells)
            + f" | {gap['mean']:+.2f} ± {gap['t95_half_width']:.2f}"
            + f" | {'/'.join(str(p['steps']) for p in seeds)}"
            + f" | {'/'.join(format(p['wall_time_s'], '.0f') for p in seeds)}"
            + f" | {'/'.join(flat_curve(p['curve']) for p in seeds)} |"
        )  # fmt: skip
    lines += ["", budgets(table), "", planner_note(table), ""]
    if "demos" in table:
        d = table["demos"]
        lines.append(
            f"Demonstrations: {d['episodes']} planner ({d['method']}) episodes of the training "
            f"split, {d['steps']} steps, {d['successes']} reaching the goal (those are cloned; "
            f"{d['left_out']} more left out: no plan). BC's steps are demonstration steps."
        )
        lines.append("")
    seeds_wall = sum(p["wall_time_s"] for m in table["methods"].values()
                     for p in m.get("per_seed", []))  # fmt: skip
    lines.append(
        "Curve flat: the last 20 % of a seed's evaluation curve on the training split gained "
        "less than 0.02 (`utamp_gym.rl.callbacks.plateaued`). Training wall time summed over "
        f"every seed of every row (evaluations during training included): {seeds_wall:.0f} s, "
        "on a shared, loaded 2-core machine (runs niced; times indicative only); load average "
        f"(1, 5, 15 min) {table['load_average']['start']} at the start and "
        f"{table['load_average']['end']} at the end of the run that wrote this table (seeds "
        "and evaluations made beforehand by `--train-only` runs are reused)."
    )
    prov = write_json(docs / "agents_v2.json", table, indent=2, default=str)
    write_markdown(docs / "agents_v2.md", "\n".join(lines) + "\n", prov)
    curves = {label: [p["curve"] for p in m["per_seed"]] for label, m in table["methods"].items()
              if m["kind"] == "learned" and any(p["curve"] for p in m["per_seed"])}  # fmt: skip
    if curves:  # success on the training split; BC's x axis counts demonstration samples
        plot_learning_curves(curves, docs / "agents_v2_curves.png",
                             f"evaluation success on {table['splits']['train']} during "
                             "training")  # fmt: skip


def planner_note(table: dict[str, Any]) -> str:
    """How much of the ceiling the planner row reaches, per split."""
    label, m = next((k, v) for k, v in table["methods"].items() if v["kind"] == "planner")
    parts = [f"{s} {m['success'][s]['successes']}/{table['achievable'][s][0]}"
             for s in table["splits"]]  # fmt: skip
    return (f"{label[0].upper()}{label[1:]}: goals reached / goals labelled achievable, per split: "
            f"{', '.join(parts)} (its plans played in the env of the utamp2x domain and checked "
            "against that domain's ground truth, as `utamp eval` does).")  # fmt: skip


def budgets(table: dict[str, Any]) -> str:
    """The budgets of the learned rows, read from their training configurations."""
    parts = []
    for label, m in table["methods"].items():
        if m["kind"] != "learned":
            continue
        c = m["per_seed"][0]["config"]
        if c["algo"] == "bc":
            epochs = c["hyperparams"].get("epochs")
            parts.append(f"{label}: {epochs} epochs over the demonstrations")
            continue
        limit = f", stopped at the first evaluation after {c['time_limit_s']:.0f} s of " \
            "training" if c.get("time_limit_s") else ""  # fmt: skip
        if c.get("stop_at_plateau"):
            limit += f" or once its curve is flat (gain < {c['stop_at_plateau']})"
        start = " from the BC policy of the same seed" if c.get("init_from") else ""
        parts.append(f"{label}: at most {c['steps']:,} env steps ({c['n_envs']} envs){start}"
                     f"{limit}, evaluated every {c['eval_every']:,} steps on "
                     f"{c['eval_episodes']} training episodes")  # fmt: skip
    return "Budgets per seed: " + "; ".join(parts) + "."


if __name__ == "__main__":
    main()
