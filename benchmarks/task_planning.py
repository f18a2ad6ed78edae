"""Plan length and planning time per goal template on procedural-v2 scenes.

Plans every achievable goal of a sample of each split (every ``--step``-th scene, or the
generator's first ``--seeds`` seeds when the split file does not hold the split yet) with a
planner method (default ``utamp2-gt``, Fast Downward ``--search``), and prints per template:
scenes, solved, median and p95 planning time (s), median / max plan length (actions).
Writes ``<out>.md`` and ``<out>.json`` with the commit and the command.

    python benchmarks/task_planning.py [--splits train test-tasks hard] [--step 10]
        [--method utamp2-gt] [--search astar-blind] [--out docs/results/task_planning]
"""

from __future__ import annotations

import argparse
import statistics
from collections import defaultdict
from typing import Any

from utamp_gym.planning.fast_downward import DEFAULT_SEARCH, SEARCH_CONFIGS
from utamp_gym.planning.methods import plan_scene
from utamp_gym.provenance import provenance, write_json, write_markdown
from utamp_gym.suites.procedural.spec import NoLayout
from utamp_gym.suites.procedural_v2 import available_splits, generate_scene, split_scenes
from utamp_gym.suites.procedural_v2.spec import SPLITS


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


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--splits", nargs="+", choices=SPLITS, default=["train", "test-tasks", "hard"])
    ap.add_argument("--step", type=int, default=10)
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--method", default="utamp2-gt")
    ap.add_argument("--search", choices=SEARCH_CONFIGS, default=DEFAULT_SEARCH)
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--out", default="docs/results/task_planning")
    args = ap.parse_args()
    rows: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for split in args.splits:
        for scene, template, achievable in _sample(split, args.step, args.seeds):
            if not achievable:
                continue
            out = plan_scene(scene, args.method, search=args.search, timeout=args.timeout)
            rows[template].append(
                {"scene": scene.name, "solved": out.solved, "time_s": out.planning_time_s,
                 "plan_length": out.plan_length}
            )  # fmt: skip
    lines = [
        f"Planning per template ({args.method}, {args.search}; splits {', '.join(args.splits)}, "
        f"achievable goals of every {args.step}th scene)",
        "",
        "| template | scenes | solved | median s | p95 s | median length | max length |",
        "|---|---|---|---|---|---|---|",
    ]
    for template in sorted(rows):
        rs = rows[template]
        times = [r["time_s"] for r in rs]
        lengths = [r["plan_length"] for r in rs if r["solved"]]
        lines.append(
            f"| {template} | {len(rs)} | {sum(r['solved'] for r in rs)} | "
            f"{statistics.median(times):.3f} | {_p95(times):.3f} | "
            f"{statistics.median(lengths) if lengths else '-'} | {max(lengths, default='-')} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    prov = provenance()
    write_markdown(f"{args.out}.md", text, prov)
    write_json(f"{args.out}.json", {"rows": rows, "args": vars(args)})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
