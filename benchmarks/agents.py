"""Learned agents on the generalisation splits, next to the planner: docs/results/agents.*.

Trains every learned baseline on the training split with `utamp train`'s functions (3 seeds),
evaluates each seed's final model on every split with `utamp eval`'s sweep (``rl:PATH`` rows,
symbolic grounding: the outcome model decides), evaluates the planner with rule-derived and
ground-truth affordances on the same scenes, and writes

* ``docs/results/agents.md``: methods x splits, success mean +- 95 % interval over the seeds
  (t interval: 4.30 x sd / sqrt(3)), the generalisation gap (train - test), steps and wall time
  per seed, the budgets, the share of each split's scenes whose goal is achievable (the
  ceiling: ~10 % are unachievable on purpose) and the machine's load average;
* ``docs/results/agents.json``: every number behind it (per seed, per split, pooled Wilson
  intervals over episodes);
* ``docs/results/agents_learning_curves.png``: evaluation success on the training split during
  training (mean and min-max band over seeds).

The splits are #22's procedural splits (``procedural-v1/<split>``, `UTampKitchenProcedural-v0`):
train on ``train``; ``test-instances`` has new instances of the training families,
``test-families`` objects of held-out families, ``test-count`` six objects (more than any
training scene).

    python benchmarks/agents.py [--seeds 3] [--ppo-steps 24576] [--ft-steps 4096]
        [--demos 300] [--bc-epochs 30] [--eval-every 4096] [--plateau GAIN] [--time-limit S]
        [--train-workers N [--executor local|ray]] [--out runs/agents]
        [--docs docs/results] [--only ppo|imitation] [--workers N]

The defaults are the budgets of docs/results/agents.md.

Runs resume: a finished seed (same configuration) and finished evaluation rows are reused.
"""

from __future__ import annotations

import argparse
import functools
import json
import statistics
import time
from pathlib import Path
from typing import Any

from compare import load  # benchmarks/ is on sys.path when run

from utamp_gym.eval.intervals import t_interval
from utamp_gym.provenance import commit, write_json, write_markdown

PLANNERS = ("utamp2-rules", "utamp2-gt")


def splits() -> tuple[dict[str, str], str, dict[str, Any]]:
    """(split name -> suite, training env id, its options): the procedural splits (the env's
    default split is ``train``)."""
    from utamp_gym.suites.procedural import SPLITS, SUITE

    return {n: f"{SUITE}/{n}" for n in SPLITS}, "UTampKitchenProcedural-v0", {}


def achievable(split_suites: dict[str, str]) -> dict[str, list[int]]:
    """Per split: [scenes whose goal the rules call achievable, scenes] (the success ceiling)."""
    from utamp_gym.suites.procedural import split_scenes

    out = {}
    for name, suite in split_suites.items():
        scenes = split_scenes(suite.rsplit("/", 1)[1])
        out[name] = [sum(g.achievable for g in scenes), len(scenes)]
    return out


def evaluate(
    method: str, suite: str, out: Path, workers: int, limit: int | None = None
) -> list[Any]:
    """`utamp eval` rows of one method on one suite (`evaluate_all`)."""
    return evaluate_all((method,), suite, out, workers, limit)[method]


def evaluate_all(
    methods: tuple[str, ...], suite: str, out: Path, workers: int, limit: int | None = None
) -> dict[str, list[Any]]:
    """`utamp eval` rows of every method on one suite (symbolic grounding, seed 0), by method:
    one sweep (so its worker processes, and the env an ``rl:PATH`` method keeps per process,
    serve every model), in the suite's own folder under `out` (so the splits can be evaluated
    by separate processes); a rerun reuses the rows it finds there."""
    from utamp_gym.eval.sweep import SweepConfig, run_sweep

    cfg = SweepConfig(suite=suite, methods=methods, grounding="symbolic", explain=False,
                      limit=limit)  # fmt: skip
    report = run_sweep(cfg, out / suite.rsplit("/", 1)[-1], workers=workers, progress=False)
    crashed = report.crashed
    if crashed:
        raise RuntimeError(f"{len(crashed)} crashed rows for {crashed[0].method} on {suite}: "
                           f"{crashed[0].failure_reason}")  # fmt: skip
    by_method: dict[str, list[Any]] = {m: [] for m in methods}
    for r in report.rows:
        by_method[r.method].append(r)
    return by_method


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--ppo-steps", type=int, default=24_576)
    p.add_argument("--ft-steps", type=int, default=4_096)
    p.add_argument("--demos", type=int, default=300, help="planner episodes for BC")
    p.add_argument("--bc-epochs", type=int, default=30)
    p.add_argument("--eval-every", type=int, default=4_096)
    p.add_argument(
        "--plateau",
        type=float,
        default=None,
        help="stop a MaskablePPO seed once the last 20 %% of its curve gains less than this "
        "(e.g. 0.02; utamp_gym.rl.callbacks.plateaued)",
    )
    p.add_argument("--workers", type=int, default=0, help="evaluation worker processes")
    p.add_argument("--limit", type=int, default=None, help="scenes per split (smoke runs)")
    p.add_argument("--train-workers", type=int, default=0, help="seeds trained in parallel")
    p.add_argument(
        "--time-limit",
        type=float,
        default=None,
        help="stop a MaskablePPO seed at its first evaluation after this many training seconds "
        "(the steps it reached are recorded)",
    )
    p.add_argument(
        "--ft-time-limit",
        type=float,
        default=None,
        help="--time-limit for the fine-tuning seeds (default: --time-limit)",
    )
    p.add_argument(
        "--executor",
        choices=("local", "ray"),
        default="local",
        help="what trains the seeds in parallel with --train-workers: local processes or Ray "
        "tasks (utamp train --executor)",
    )
    p.add_argument("--out", default="runs/agents")
    p.add_argument("--docs", default="docs/results")
    p.add_argument(
        "--only",
        choices=("ppo", "imitation"),
        default=None,
        help="only train these rows (MaskablePPO; or demos, BC and fine-tuning) and stop: two "
        "processes can train the two families at once, a later full run reuses both",
    )
    p.add_argument(
        "--rewrite", action="store_true", help="only rewrite the docs from the measured agents.json"
    )
    return p


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    if args.rewrite:
        write(json.loads((Path(args.docs) / "agents.json").read_text()), Path(args.docs))
        return

    from utamp_gym.data.record import dataset_id
    from utamp_gym.distributed import make_executor
    from utamp_gym.rl.seeds import train_seeds

    out, docs = Path(args.out), Path(args.docs)
    load_at_start = load()
    split_suites, env_id, env_opts = splits()
    train_suite = split_suites["train"]
    common = {"env_id": env_id, "masks": "geometric", "interface": "objects",
              "eval_episodes": 30, "progress": False, **env_opts}  # fmt: skip
    if args.train_workers:
        common["executor"] = make_executor(args.executor, workers=args.train_workers)
    runs: dict[str, dict[str, Any]] = {}

    start = time.perf_counter()
    if args.only in (None, "ppo"):
        ppo = train_seeds(args.seeds, out=out / "ppo", algo="maskable-ppo",
                          steps=args.ppo_steps, eval_every=args.eval_every,
                          stop_at_plateau=args.plateau, time_limit_s=args.time_limit,
                          **common)  # fmt: skip
        runs["MaskablePPO, slot transformer"] = {"dir": out / "ppo", "agg": ppo}
        if args.only:
            return
    demo = record_or_reuse_demos(train_suite, args.demos, out / "demos")
    bc = train_seeds(args.seeds, out=out / "bc", algo="bc", demos=demo["path"],
                     hyperparams={"epochs": args.bc_epochs}, **common)  # fmt: skip
    runs[f"BC from {demo['episodes']} planner episodes"] = {"dir": out / "bc", "agg": bc}
    ft_kwargs = {"algo": "maskable-ppo", "steps": args.ft_steps,
                 "eval_every": min(args.eval_every, max(1, args.ft_steps // 3)),
                 "stop_at_plateau": args.plateau,
                 "time_limit_s": args.ft_time_limit or args.time_limit,
                 **{k: v for k, v in common.items() if k != "executor"}}  # fmt: skip
    ft_aggs = fine_tune(args.seeds, out, ft_kwargs, common.get("executor"))
    runs["BC, then MaskablePPO fine-tuning"] = {"dir": out / "ft", "aggs": ft_aggs}
    if args.only:
        return
    train_wall = time.perf_counter() - start

    table: dict[str, Any] = {
        "splits": split_suites,
        "limit": args.limit,
        "env_id": env_id,
        "methods": {},
        "demos": {
            "dataset": dataset_id(train_suite, "macro", "utamp2-gt"),
            "episodes": demo["episodes"],
            "steps": demo["steps"],
            "left_out": len(demo.get("left_out", {})),
        },
    }
    for label, run in runs.items():
        per_seed = []
        aggs = run.get("aggs") or [run["agg"]]
        seed_runs = [Path(r) for a in aggs for r in a["runs"]]
        for run_dir in seed_runs:
            report = json.loads((run_dir / "train.json").read_text())
            model = run_dir / "model.zip"
            success = {}
            for split, suite in split_suites.items():
                rows = evaluate(f"rl:{model}", suite, out / "eval" / run_dir.relative_to(out),
                                args.workers, args.limit)  # fmt: skip
                success[split] = {
                    "rate": sum(r.success for r in rows) / len(rows),
                    "n": len(rows),
                    "successes": sum(r.success for r in rows),
                }
            per_seed.append({"run": str(run_dir), "seed": report["config"]["seed"],
                             "steps": report["steps"], "wall_time_s": report["wall_time_s"],
                             "train_time_s": report["train_time_s"], "curve": report["curve"],
                             "success": success})  # fmt: skip
        table["methods"][label] = {"kind": "learned", "per_seed": per_seed,
                                   "config": json.loads((seed_runs[0] / "train.json")
                                                        .read_text())["config"]}  # fmt: skip
    for planner in PLANNERS:
        success = {}
        for split, suite in split_suites.items():
            rows = evaluate(planner, suite, out / "eval" / planner, args.workers, args.limit)
            success[split] = {"rate": sum(r.success for r in rows) / len(rows), "n": len(rows),
                              "successes": sum(r.success for r in rows),
                              "planning_time_s": statistics.fmean(
                                  r.planning_time_s or 0.0 for r in rows)}  # fmt: skip
        table["methods"][f"planner ({planner})"] = {"kind": "planner", "success": success}
    table["load_average"] = {"start": load_at_start, "end": load()}
    table["total_wall_time_s"] = round(time.perf_counter() - start, 1)
    table["training_wall_time_s"] = round(train_wall, 1)
    write(table, docs)


def _fine_tune_seed(seed: int, *, out: str, kwargs: dict[str, Any]) -> tuple[int, Any]:
    """Fine-tune the BC model of `seed` (``out/bc/seed_<s>``) into ``out/ft/from_bc_<s>``."""
    from utamp_gym.rl.seeds import train_seeds

    init = Path(out) / "bc" / f"seed_{seed}" / "model.zip"
    return seed, train_seeds(1, seed=seed, out=Path(out) / "ft" / f"from_bc_{seed}",
                             init_from=str(init), **kwargs)  # fmt: skip


def fine_tune(seeds: int, out: Path, kwargs: dict[str, Any], executor: Any) -> list[Any]:
    """Each fine-tuning seed from the BC seed of its number: one after another, or as the
    executor's parallel tasks (a finished seed is reused either way)."""
    task = functools.partial(_fine_tune_seed, out=str(out), kwargs=kwargs)
    if executor is None:
        return [task(s)[1] for s in range(seeds)]
    done: dict[int, Any] = {}
    executor.run(task, list(range(seeds)), lambda item: done.__setitem__(*item),
                 lambda s, reason: (s, reason))  # fmt: skip
    failed = {s: r for s, r in done.items() if isinstance(r, str)}
    if failed:
        raise RuntimeError(f"fine-tuning failed: {failed}")
    return [done[s] for s in range(seeds)]


def record_or_reuse_demos(suite: str, episodes: int, root: Path) -> dict[str, Any]:
    """`utamp demos`' recording of `episodes` planner episodes of `suite` (reset seeds from
    100,000, symbolic grounding, objects interface), or the one already under `root`."""
    from utamp_gym.data.record import record_demos

    marker = root / "demos.json"
    want = {"suite": suite, "requested": episodes, "seed": 100_000}
    if marker.is_file():
        done = json.loads(marker.read_text())
        if {k: done.get(k) for k in want} == want and Path(done["path"]).is_dir():
            return done
    demo = record_demos(suite, episodes, root, seed=100_000,
                        env_options={"grounding": "symbolic", "masks": "geometric",
                                     "interface": "objects"})  # fmt: skip
    done = {**want, "path": str(demo.path), "episodes": demo.episodes, "steps": demo.steps,
            "left_out": {**demo.failed, **demo.unsolvable}}  # fmt: skip
    marker.write_text(json.dumps(done, indent=2) + "\n")
    return done


def write(table: dict[str, Any], docs: Path) -> None:
    """agents.json, agents.md and the learning curves from the measured table."""
    from utamp_gym.eval.intervals import wilson_interval
    from utamp_gym.rl.callbacks import plot_learning_curves

    docs.mkdir(parents=True, exist_ok=True)
    splits_ = list(table["splits"])
    train = splits_[0]
    ceiling = table.setdefault("achievable", achievable(table["splits"]))
    limit = table.get("limit")
    scenes = "all its scenes" if limit is None else f"its first {limit} scenes only (--limit)"
    lines = [
        f"Training split: `{table['splits'][train]}` ({table['env_id']}, objects interface, "
        f"geometric masks, symbolic grounding); every split evaluated on {scenes}, seed 0, "
        "symbolic grounding, deterministic masked policy, 10 steps per object. Learned rows: "
        "mean over seeds ± 95 % t interval; planner rows: one deterministic run per scene.",
        "",
        "| method | seeds | "
        + " | ".join(
            f"{s} (`{table['splits'][s]}`, {ceiling[s][0]}/{ceiling[s][1]} achievable)"
            for s in splits_
        )
        + " | gap train − test (mean) | steps / seed | wall s / seed | curve flat / seed |",
        "|---" * (len(splits_) + 6) + "|",
    ]
    curves = {}
    for label, m in table["methods"].items():
        if m["kind"] == "planner":
            cells = [f"{m['success'][s]['rate']:.2f} (n={m['success'][s]['n']})" for s in splits_]
            gaps = [m["success"][train]["rate"] - m["success"][s]["rate"] for s in splits_[1:]]
            lines.append(f"| {label} | – | " + " | ".join(cells)
                         + f" | {statistics.fmean(gaps):+.2f} | – | – | – |")  # fmt: skip
            continue
        seeds = m["per_seed"]
        cells, means = [], {}
        for s in splits_:
            rates = [p["success"][s]["rate"] for p in seeds]
            mean, half = t_interval(rates)
            means[s] = mean
            k = sum(p["success"][s]["successes"] for p in seeds)
            n = sum(p["success"][s]["n"] for p in seeds)
            m.setdefault("summary", {})[s] = {"mean": mean, "t95_half_width": half,
                                              "pooled_wilson95": wilson_interval(k, n)}  # fmt: skip
            cells.append(f"{mean:.2f} ± {half:.2f}")
        gaps = [means[train] - means[s] for s in splits_[1:]]
        steps = "/".join(str(p["steps"]) for p in seeds)
        wall = "/".join(f"{p['wall_time_s']:.0f}" for p in seeds)
        flat = "/".join(flat_curve(p["curve"]) for p in seeds)
        gap = statistics.fmean(gaps)
        lines.append(f"| {label} | {len(seeds)} | " + " | ".join(cells)
                     + f" | {gap:+.2f} | {steps} | {wall} | {flat} |")  # fmt: skip
        curves[label] = [p["curve"] for p in seeds]
    train_wall = sum(p["wall_time_s"] for m in table["methods"].values()
                     for p in m.get("per_seed", []))  # fmt: skip
    lines += ["", budgets(table), ""]
    lines += [
        "Curve flat: the last 20 % of a seed's evaluation curve on the training split gained less "
        "than 0.02 success (running mean of three evaluations; `utamp_gym.rl.callbacks."
        "plateaued`, at least 10 evaluations); BC's curve counts demonstration samples.",
        "",
    ]
    lines += [
        f"Demonstrations: {table['demos']['episodes']} planner (utamp2-gt) episodes "
        f"({table['demos'].get('left_out', 0)} more left out: no plan, the goal unreachable), "
        f"{table['demos']['steps']} steps, of the training split (`{table['demos']['dataset']}`); "
        "BC's steps are those demonstration steps (its curve counts samples seen). Training "
        f"wall time summed over every seed of every learned row: {train_wall:.0f} s, on a shared "
        "2-core machine (runs niced; times are indicative only)"
        + (
            f"; load average (1, 5, 15 min) {table['load_average']['start']} at the start and "
            f"{table['load_average']['end']} at the end of the run that wrote this table."
            if "load_average" in table
            else "."
        ),
    ]
    prov = write_json(docs / "agents.json", table, indent=2, default=str)
    write_markdown(docs / "agents.md", "\n".join(lines) + "\n", prov)
    # the learning curves: success on the training split; BC's x axis counts samples seen
    plot_learning_curves(
        curves,
        docs / "agents_learning_curves.png",
        f"evaluation success on {table['splits'][train]} during training",
    )


def flat_curve(curve: list[dict[str, Any]]) -> str:
    """Whether the last 20 % of a curve gained less than 0.02 (`plateaued`): "yes" or "no"."""
    from utamp_gym.rl.callbacks import EvalPoint, plateaued

    return "yes" if plateaued([EvalPoint(**p) for p in curve], 0.02) else "no"


def budgets(table: dict[str, Any]) -> str:
    """The budgets of the learned rows, read from their training configurations."""
    parts = []
    for label, m in table["methods"].items():
        if m["kind"] != "learned":
            continue
        c = m["config"]
        if c["algo"] == "bc":
            epochs = c["hyperparams"].get("epochs", "default")
            parts.append(f"{label}: {epochs} epochs over the demonstrations")
        else:
            start = " from the cloned policy of the same seed" if c.get("init_from") else ""
            parts.append(f"{label}: {c['steps']:,} env steps ({c['n_envs']} envs){start}, "
                         f"evaluated every {c['eval_every']:,} steps")  # fmt: skip
    episodes = next(m["config"]["eval_episodes"] for m in table["methods"].values()
                    if m["kind"] == "learned")  # fmt: skip
    return ("Budgets per seed: " + "; ".join(parts) + f". Evaluation during training: "
            f"{episodes} fixed episodes of the training split.")  # fmt: skip


if __name__ == "__main__":
    main()
