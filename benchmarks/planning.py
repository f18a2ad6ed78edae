"""Planning benchmark: our fast path vs Fast Downward's own driver, per object count.

For every pick-place scene (or every k-th with --stride) and both domains, plan with
the fast path (our grounder + SAS + search binary, in this process) and with
`fast-downward.py` running the same search on the same PDDL files, in the same run. Prints
median and mean ± std of the planning time per object count, the ratio of ours to the
driver, and which U-TAMP-1 plans violate the ground-truth affordances.

    python benchmarks/planning.py [--stride 1] [--suite pick-place] [--search astar-lmcut]
                                  [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path

from utamp_gym.planning.crosscheck import check_against_ground_truth
from utamp_gym.planning.fast_downward import DEFAULT_SEARCH, SEARCH_CONFIGS, solve_with_driver
from utamp_gym.planning.methods import plan_scene
from utamp_gym.suites import suite_scenes

METHODS = ("utamp2-gt", "utamp1")


def _stats(xs: list[float]) -> str:
    if not xs:
        return "-"
    sd = statistics.stdev(xs) if len(xs) > 1 else 0.0
    return f"{statistics.median(xs):.4f} | {statistics.mean(xs):.4f} ± {sd:.4f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="pick-place")
    ap.add_argument("--stride", type=int, default=1, help="use every k-th scene")
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--search", choices=SEARCH_CONFIGS, default=DEFAULT_SEARCH)
    ap.add_argument("--json", help="also write the raw rows here")
    args = ap.parse_args()

    rows = []
    scenes = suite_scenes(args.suite)[:: args.stride]
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            for method in METHODS:
                if method == "utamp1" and args.suite == "sliding":
                    continue
                ours = plan_scene(scene, method, timeout=args.timeout, search=args.search)
                d, p = Path(tmp, "domain.pddl"), Path(tmp, "problem.pddl")
                d.write_text(ours.domain)
                p.write_text(ours.problem)
                driver = solve_with_driver(d, p, search=args.search, timeout=args.timeout)
                violation = None
                if method == "utamp1" and ours.solved:
                    check = check_against_ground_truth(scene, ours.plan)
                    violation = None if check.valid else check.message
                rows.append(
                    {
                        "scene": scene.name,
                        "n": scene.n_objects,
                        "method": method,
                        "solved": ours.solved,
                        "plan_length": ours.plan_length,
                        "ours_s": ours.planning_time_s,
                        "driver_s": driver.planning_time_s,
                        "driver_solved": driver.solved,
                        "violation": violation,
                    }
                )
                print(
                    f"{scene.name} {method:10s} ours {ours.planning_time_s:.3f}s "
                    f"driver {driver.planning_time_s:.3f}s",
                    flush=True,
                )

    print(f"\n## Planning time on {args.suite} ({len(scenes)} scenes), seconds")
    print(
        "| method | n | scenes | solved | ours: median | mean ± std | driver: median | mean ± std "
        "| ratio of medians |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for method in METHODS:
        for n in (2, 3, 4, 5):
            sel = [r for r in rows if r["method"] == method and r["n"] == n]
            if not sel:
                continue
            ours = [r["ours_s"] for r in sel]
            drv = [r["driver_s"] for r in sel]
            ratio = statistics.median(ours) / statistics.median(drv)
            print(
                f"| {method} | {n} | {len(sel)} | {sum(r['solved'] for r in sel)} | "
                f"{_stats(ours)} | {_stats(drv)} | {ratio:.2f} |"
            )
    u1 = [r for r in rows if r["method"] == "utamp1" and r["solved"]]
    bad = [r for r in u1 if r["violation"]]
    if u1:
        print(
            f"\n## U-TAMP-1 plans violating the ground-truth affordances: {len(bad)} of {len(u1)}"
        )
        for r in bad:
            print(f"- {r['scene']}: {r['violation']}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
