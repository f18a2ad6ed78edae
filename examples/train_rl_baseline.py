"""Reproduce the RL baseline table: three agents, several seeds, next to the planner.

    python examples/train_rl_baseline.py [--out out/rl/baselines] [--seeds 3]
        [--configs affordances,geometric,none] [--steps-affordances 100000]
        [--steps-geometric 300000] [--steps-none 300000] [--evals 10] [--physics-per-count 4]
        [--physics-configs affordances,geometric] [--train-only]
        [--figure docs/results/rl_learning_curves.png]

The agents (all on UTampKitchen-v0, 2-5 objects mixed, symbolic grounding, reward shaping):

* ``affordances``: MaskablePPO with the U-TAMP-2 masks under ground-truth affordances (the
  planner's knowledge handed to the agent);
* ``geometric``: MaskablePPO with geometric masks; what the ground truth forbids fails
  through the symbolic outcome model (`utamp_gym.symbolic.outcome`), so affordances are learned;
* ``none``: PPO without masks (masks "none": every action of the scene is shown and allowed;
  the outcome model rejects the impossible ones).

Each configuration trains `--seeds` runs (`train_seeds`; a finished configuration is reused,
so re-running only re-evaluates), then every seed's final model is evaluated through the
evaluation harness (``rl:PATH`` methods, rows next to ``utamp2-gt`` in one ``results.csv``):
on every pick-place scene in symbolic grounding, and (`--physics-configs`) on a stratified
subset in physics (`--physics-per-count` scenes per object count). Prints the table (steps
and wall time to 90 % evaluation success, or the best success within the budget; success
per object count, mean ± std over seeds) and writes it to ``OUT/baselines.md`` plus the
learning curves of all configurations in one figure.
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from utamp_gym.backend import DEFAULT_POSE_NOISE
from utamp_gym.eval.plots import write_plots
from utamp_gym.eval.records import ResultRow, ResultsFile
from utamp_gym.eval.runner import EvalTask, run_task
from utamp_gym.eval.summary import summarize, write_summary
from utamp_gym.provenance import commit, write_markdown
from utamp_gym.rl.callbacks import plot_learning_curves
from utamp_gym.rl.seeds import train_seeds
from utamp_gym.suites import suite_scenes


@dataclass(frozen=True)
class Config:
    name: str
    algo: str
    masks: str
    label: str


CONFIGS = {
    c.name: c
    for c in (
        Config("affordances", "maskable-ppo", "affordances", "MaskablePPO, affordance masks"),
        Config("geometric", "maskable-ppo", "geometric", "MaskablePPO, geometric masks"),
        Config("none", "ppo", "none", "PPO, no masks"),
    )
}
PLANNER = "utamp2-gt"


def trained(cfg: Config, out: Path, seeds: int, steps: int, evals: int) -> dict[str, Any]:
    """The aggregate of a configuration, training it unless a finished one is there."""
    agg_path = out / "aggregate.json"
    if agg_path.is_file():
        agg = json.loads(agg_path.read_text())
        if len(agg["seeds"]) == seeds and agg["config"]["steps"] == steps:
            return agg
    return train_seeds(
        seeds, out=out, algo=cfg.algo, masks=cfg.masks, steps=steps, eval_every=steps // evals,
        eval_episodes=60, progress=False,
    )  # fmt: skip


def evaluate(
    methods: Sequence[str], scenes: Sequence[str], grounding: str, out: Path
) -> list[ResultRow]:
    """Rows of every (scene, method) in one results.csv (resumable), plus summary.md/json."""
    out.mkdir(parents=True, exist_ok=True)
    results = ResultsFile(out / "results.csv")
    for method in methods:  # one model at a time: the harness caches the loaded policy
        for scene in scenes:
            noise = None if grounding == "symbolic" else DEFAULT_POSE_NOISE
            task = EvalTask(scene, method, 0, grounding, pose_noise=noise)
            if task.key not in results:
                results.append(run_task(task))
    results.sort()
    rows = [r for r in results.rows.values() if r.method in methods and r.scene in scenes]
    summary = summarize(
        rows,
        context={"suite": "pick-place", "grounding": grounding, "scenes": len(scenes), "seeds": 1},
    )
    write_summary(out, summary)
    write_plots(out, summary)
    return rows


def stratified(per_count: int) -> list[str]:
    """`per_count` pick-place scenes of each object count, spread over the suite."""
    out = []
    for n in (2, 3, 4, 5):
        names = [s.name for s in suite_scenes("pick-place") if s.n_objects == n]
        step = max(1, len(names) // per_count)
        out += names[::step][:per_count]
    return out


def by_count(rows: Sequence[ResultRow], method: str) -> dict[int, float]:
    mine = [r for r in rows if r.method == method]
    return {
        n: statistics.fmean(r.success for r in mine if r.n_objects == n)
        for n in sorted({r.n_objects for r in mine})
    }


def cell(values: Sequence[float]) -> str:
    if len(values) == 1:
        return f"{values[0]:.2f}"
    return f"{statistics.fmean(values):.2f} ± {statistics.stdev(values):.2f}"


def table(
    aggs: dict[str, dict[str, Any]],
    sym: list[ResultRow],
    phys: list[ResultRow],
    models: dict[str, list[str]],
) -> str:
    counts = (2, 3, 4, 5)
    head = [
        "agent",
        "seeds",
        "budget (steps)",
        "≥ 90 % at (steps)",
        "≥ 90 % at (train s)",
        "best eval success",
    ]
    head += [f"symbolic n={n}" for n in counts] + ["physics (subset)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, agg in aggs.items():
        cfg = CONFIGS[name]
        st, tt = agg["steps_to_target"], agg["time_to_target_s"]
        reached = f"{agg['reached']}/{len(agg['seeds'])}"
        to90 = (
            f"{st['mean']:.0f} ({reached} seeds)"
            if st["mean"] is not None
            else f"not reached ({reached})"
        )
        t90 = f"{tt['mean']:.0f}" if tt["mean"] is not None else "–"
        best = f"{agg['best_success']['mean']:.2f} ± {agg['best_success']['std']:.2f}"
        sym_counts = [by_count(sym, m) for m in models[name]]
        phys_rate = [
            statistics.fmean(r.success for r in phys if r.method == m)
            for m in models[name]
            if any(r.method == m for r in phys)
        ]
        row = [cfg.label, str(len(agg["seeds"])), str(agg["config"]["steps"]), to90, t90, best]
        row += [cell([c[n] for c in sym_counts if n in c]) for n in counts]
        row.append(cell(phys_rate) if phys_rate else "–")
        lines.append("| " + " | ".join(row) + " |")
    planner_sym = by_count(sym, PLANNER)
    planner_phys = [r.success for r in phys if r.method == PLANNER]
    row = ["Fast Downward planner (utamp2-gt)", "–", "–", "–", "–", "–"]
    row += [f"{planner_sym.get(n, float('nan')):.2f}" for n in counts]
    row.append(f"{statistics.fmean(planner_phys):.2f}" if planner_phys else "–")
    lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/rl/baselines")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--configs", default="affordances,geometric,none")
    ap.add_argument("--steps-affordances", type=int, default=100_000)
    ap.add_argument("--steps-geometric", type=int, default=300_000)
    ap.add_argument("--steps-none", type=int, default=300_000)
    ap.add_argument(
        "--physics-per-count", type=int, default=4, help="physics scenes per object count (0: none)"
    )
    ap.add_argument("--figure", default=None, help="also write the learning curves here")
    ap.add_argument("--evals", type=int, default=10, help="evaluations per training run")
    ap.add_argument(
        "--physics-configs",
        default="affordances,geometric",
        help="agents also evaluated in physics (with the planner)",
    )
    ap.add_argument("--train-only", action="store_true", help="train (or reuse), no evaluation")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    out = Path(args.out)
    names = [c.strip() for c in args.configs.split(",") if c.strip()]
    aggs, models = {}, {}
    for name in names:
        cfg = CONFIGS[name]
        steps = getattr(args, f"steps_{name}")
        aggs[name] = trained(cfg, out / name, args.seeds, steps, args.evals)
        models[name] = [f"rl:{Path(run) / 'model.zip'}" for run in aggs[name]["runs"]]
        agg = aggs[name]
        print(
            f"{cfg.label}: reached 90 % in {agg['reached']}/{len(agg['seeds'])} seeds, "
            f"best success {agg['best_success']['mean']:.2f}",
            flush=True,
        )
    curves = {}
    for name in names:
        runs = [
            json.loads((Path(r) / "train.json").read_text())["curve"] for r in aggs[name]["runs"]
        ]
        curves[CONFIGS[name].label] = runs
    figure = out / "learning_curves.png"
    title = (
        f"UTampKitchen-v0, 2-5 objects, symbolic grounding, {args.seeds} seeds (mean, min-max band)"
    )
    plot_learning_curves(curves, figure, title, 0.9)
    if args.figure:
        plot_learning_curves(curves, Path(args.figure), title, 0.9)
    if args.train_only:
        return
    methods = [PLANNER, *(m for name in names for m in models[name])]
    scenes = [s.name for s in suite_scenes("pick-place")]
    sym = evaluate(methods, scenes, "symbolic", out / "eval-symbolic")
    phys: list[ResultRow] = []
    in_physics = [c.strip() for c in args.physics_configs.split(",") if c.strip() in names]
    if args.physics_per_count > 0 and in_physics:
        phys_methods = [PLANNER, *(m for name in in_physics for m in models[name])]
        subset = stratified(args.physics_per_count)
        phys = evaluate(phys_methods, subset, "physics", out / "eval-physics")
    text = table(aggs, sym, phys, models)
    write_markdown(out / "baselines.md", text)
    print(text)


if __name__ == "__main__":
    main()
