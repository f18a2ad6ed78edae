"""The training runs of benchmarks/agents.py, before (or without) their split evaluation.

For each finished seed of each learned row under ``--out`` (its ``train.json``): the steps it
reached against its budget, what stopped it (the step budget, a flat curve, the time limit),
whether its curve is flat (`agents.flat_curve`: the last 20 % gained less than 0.02), its
success in the evaluations during training (30 fixed episodes of the training split), and
its training and wall time. Writes ``<docs>/agents_training.{md,json}`` and
``agents_training_curves.png``; a long run can be reported before it is evaluated.

    python benchmarks/agents_training.py [--out runs/agents] [--docs docs/results]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import write_results
from agents import flat_curve, load

from utamp_gym.provenance import commit

#: the training runs of each learned row under --out (train.json of every finished seed)
ROW_RUNS = {"MaskablePPO, slot transformer": "ppo/seed_*", "BC": "bc/seed_*",
            "BC, then MaskablePPO fine-tuning": "ft/from_bc_*/seed_*"}  # fmt: skip


def training_summary(out: Path, docs: Path) -> None:
    """``agents_training.{md,json}`` and ``agents_training_curves.png`` from the finished
    training runs under `out` (module docstring)."""
    from utamp_gym.rl.callbacks import plot_learning_curves

    docs.mkdir(parents=True, exist_ok=True)
    rows, curves = [], {}
    for label, pattern in ROW_RUNS.items():
        for run in sorted(out.glob(pattern)):
            if not (run / "train.json").is_file():
                continue
            r = json.loads((run / "train.json").read_text())
            c = r["config"]
            flat = flat_curve(r["curve"]) == "yes"
            budget = c["steps"]
            limit = c.get("time_limit_s")
            if c["algo"] == "bc":
                why = f"{r['hyperparams'].get('epochs')} epochs"
            elif r["steps"] >= budget:
                why = "step budget"
            elif flat and c.get("stop_at_plateau") is not None:
                why = "curve flat"
            else:
                why = f"time limit ({limit:.0f} s training)" if limit else "stopped"
            rows.append({"row": label, "seed": c["seed"], "run": str(run), "steps": r["steps"],
                         "budget": budget, "stopped_by": why, "curve_flat": flat,
                         "final_success": r["final_success"],
                         "best_success": max(p["success_rate"] for p in r["curve"]),
                         "train_time_s": r["train_time_s"], "wall_time_s": r["wall_time_s"],
                         "curve": r["curve"]})  # fmt: skip
            curves.setdefault(label, []).append(r["curve"])
    lines = [
        "| row | seed | steps reached | budget | stopped by | curve flat (last 20 % gains "
        "< 0.02) | training-split success at the end (30 episodes) | best | training s | "
        "wall s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['row']} | {r['seed']} | {r['steps']:,} "
            f"| {'–' if r['row'] == 'BC' else format(r['budget'], ',')} | {r['stopped_by']} "
            f"| {'yes' if r['curve_flat'] else 'no'} | {r['final_success']:.2f} "
            f"| {r['best_success']:.2f} | {r['train_time_s']:.0f} | {r['wall_time_s']:.0f} |"
        )
    lines += [
        "",
        "Training runs only: the success column is the evaluation during training (30 fixed "
        "episodes of the training split, deterministic masked policy); the four splits are "
        "evaluated by the full run (`docs/results/agents.md`). BC's steps are demonstration "
        f"steps. Run folder `{out}`; shared 2-core machine, runs niced, load average "
        f"{load()} when this summary was written.",
    ]
    data = {"rows": rows, "load_average": load(), "out": str(out)}
    write_results(docs, "agents_training", data, "\n".join(lines) + "\n", indent=1, default=str)
    plot_learning_curves(curves, docs / "agents_training_curves.png",
                         "evaluation success on procedural-v1/train during training")  # fmt: skip
    print("\n".join(lines))


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="runs/agents", help="benchmarks/agents.py's --out")
    p.add_argument("--docs", default="docs/results")
    return p


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    training_summary(Path(args.out), Path(args.docs))


if __name__ == "__main__":
    main()
