"""Plan length, planning time and nodes expanded per goal template on procedural-v2 scenes,
for several Fast Downward search configurations side by side.

Plans every achievable goal of a sample of each split (every ``--step``-th scene, every scene
of ``hard``; the generator's first ``--seeds`` seeds when the split file does not hold the
split yet) with a planner method (default: the split file's labeller, `spec.LABEL_METHOD`)
under each ``--searches`` configuration, and prints per (configuration, template): scenes,
solved, median and p95 planning time (s), median / max plan length (actions), median / max
nodes Fast Downward expanded; then the same for the hard suite alone, and the worst median
planning time per template against the 1 s target. Each scene is planned cold (a new
planner per scene and configuration). Writes ``<out>.md`` and ``<out>.json`` with the commit
and the command.

    python benchmarks/task_planning.py [--splits train test-tasks hard] [--step 10]
        [--searches astar-blind lama-first] [--out docs/results/task_planning]
"""

from __future__ import annotations

import argparse
import statistics
from collections import defaultdict
from typing import Any

from utamp_gym.planning.downward import PlanResult
from utamp_gym.planning.fast_downward import SEARCH_CONFIGS
from utamp_gym.planning.methods import method_spec, plan_scene
from utamp_gym.planning.state_planner import StatePlanner
from utamp_gym.provenance import provenance, write_json, write_markdown
from utamp_gym.suites.procedural.spec import NoLayout
from utamp_gym.suites.procedural_v2 import available_splits, generate_scene, split_scenes
from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD, SPLITS

TARGET_S = 1.0  # the planner's median per template stays within this


class _Recording(StatePlanner):
    """A state planner that keeps its last result (for the nodes Fast Downward expanded)."""

    last: PlanResult | None = None

    def plan(self, *args: Any, **kwargs: Any) -> PlanResult:
        self.last = super().plan(*args, **kwargs)
        return self.last


def _sample(split: str, step: int, seeds: int) -> list[tuple[Any, str, bool]]:
    """(scene, template, achievable or not known) of the split's sample."""
    if split in available_splits():
        return [(g.scene, g.template, g.achievable) for g in split_scenes(split)[::step]]
    out = []
    for seed in range(seeds):
        try:
            g = generate_scene(split, seed)
        except NoLayout:
            continue
        out.append((g.scene, g.template, True))
    return out


def _p95(xs: list[float]) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, round(0.95 * (len(xs) - 1)))]


def _table(title: str, rows: dict[tuple[str, str], list[dict[str, Any]]]) -> list[str]:
    lines = [
        title,
        "",
        "| search | template | scenes | solved | median s | p95 s | median length | "
        "max length | median expanded | max expanded |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (search, template), rs in sorted(rows.items()):
        times = [r["time_s"] for r in rs]
        lengths = [r["plan_length"] for r in rs if r["solved"]]
        nodes = [r["expanded"] for r in rs if r["expanded"] is not None]
        lines.append(
            f"| {search} | {template} | {len(rs)} | {sum(r['solved'] for r in rs)} | "
            f"{statistics.median(times):.3f} | {_p95(times):.3f} | "
            f"{statistics.median(lengths) if lengths else '-'} | {max(lengths, default='-')} | "
            f"{statistics.median(nodes) if nodes else '-'} | {max(nodes, default='-')} |"
        )
    return lines


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--splits", nargs="+", choices=SPLITS, default=list(SPLITS))
    ap.add_argument("--step", type=int, default=10, help="every STEP-th scene (hard: all)")
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--method", default=LABEL_METHOD)
    ap.add_argument("--searches", nargs="+", choices=SEARCH_CONFIGS,
                    default=["astar-blind", "lama-first"])  # fmt: skip
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--out", default="docs/results/task_planning")
    return ap


def main() -> int:
    args = build_parser().parse_args()
    domain = method_spec(args.method).domain
    rows: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    hard: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for split in args.splits:
        step = 1 if split == "hard" else args.step
        for scene, template, achievable in _sample(split, step, args.seeds):
            if not achievable:
                continue
            for search in args.searches:
                planner = _Recording(domain, search=search, timeout=args.timeout)
                out = plan_scene(scene, args.method, timeout=args.timeout, planner=planner)
                row = {"scene": scene.name, "solved": out.solved, "time_s": out.planning_time_s,
                       "plan_length": out.plan_length,
                       "expanded": planner.last.expanded if planner.last else None}  # fmt: skip
                rows[search, template].append(row)
                if split == "hard":
                    hard[search, template].append(row)
    lines = _table(
        f"Planning per template ({args.method}; splits {', '.join(args.splits)}: achievable "
        f"goals of every {args.step}th scene, every hard scene)",
        rows,
    )
    if hard:
        lines += ["", *_table("The hard suite alone (procedural-v2/hard)", hard)]
    worst = max(statistics.median(r["time_s"] for r in rs) for rs in rows.values())
    verdict = "met" if worst <= TARGET_S else "NOT met"
    lines += ["", f"Worst median planning time over (search, template): {worst:.3f} s "
              f"(target <= {TARGET_S:.0f} s: {verdict})"]  # fmt: skip
    text = "\n".join(lines) + "\n"
    print(text)
    prov = provenance()
    write_markdown(f"{args.out}.md", text, prov)
    write_json(
        f"{args.out}.json",
        {"rows": {f"{s}/{t}": rs for (s, t), rs in sorted(rows.items())},
         "worst_median_s": worst, "args": vars(args)},
    )  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
