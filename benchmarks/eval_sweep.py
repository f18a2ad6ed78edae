"""Wall time of the full `utamp eval` sweep of both suites, symbolic and/or physics grounding.

Runs every scene of pick-place and sliding with the four offline methods (utamp1 is
skipped on sliding) from scratch into a fresh directory, then prints the wall time per
suite and in total against the targets (symbolic <= 2 min; physics <= 10 min on 2
cores), and each method's success rate and planning time.

    python benchmarks/eval_sweep.py [--grounding symbolic|physics|both] [--workers 2]
                                    [--seeds 1] [--limit N] [--keep DIR] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from compare import cpu_s  # benchmarks/ is on sys.path when run

from utamp_gym.eval.sweep import DEFAULT_METHODS, SweepConfig, run_sweep, write_outputs

TARGETS_S = {"symbolic": 120.0, "physics": 600.0}
SUITES = ("pick-place", "sliding")


def _sweep(grounding: str, args: argparse.Namespace, root: Path) -> dict[str, object]:
    out: dict[str, object] = {"grounding": grounding, "workers": args.workers, "suites": {}}
    start, cpu0 = time.perf_counter(), cpu_s()
    for suite in SUITES:
        cfg = SweepConfig(
            suite, DEFAULT_METHODS, seeds=args.seeds, grounding=grounding, limit=args.limit
        )
        report = run_sweep(cfg, root / grounding / suite, workers=args.workers, progress=True)
        summary = write_outputs(report)
        out["suites"][suite] = {  # type: ignore[index]
            "runs": len(report.rows),
            "wall_time_s": round(report.wall_time_s, 2),
            "notes": report.notes,
            "methods": {
                m["label"]: {
                    "runs": m["runs"],
                    "success_rate": m["success_rate"],
                    "planning_time_mean_s": m["planning_time_mean_s"],
                    "planning_time_std_s": m["planning_time_std_s"],
                    "affordance_f1_mean": m["affordance_f1_mean"],
                    "crashed": m["crashed"],
                }
                for m in summary["methods"]
            },
        }
    out["total_wall_time_s"] = round(time.perf_counter() - start, 2)
    out["cpu_time_s"] = round(cpu_s() - cpu0, 2)
    out["load_average"] = os.getloadavg()
    return out


def _print(res: dict[str, object]) -> None:
    g = str(res["grounding"])
    print(f"\n== {g} grounding, {res['workers']} worker(s)")
    for suite, s in res["suites"].items():  # type: ignore[attr-defined]
        print(f"{suite}: {s['runs']} runs in {s['wall_time_s']:.1f} s")
        for note in s["notes"]:
            print(f"  note: {note}")
        for label, m in s["methods"].items():
            t, sd = m["planning_time_mean_s"], m["planning_time_std_s"]
            f1 = "" if m["affordance_f1_mean"] is None else f", F1 {m['affordance_f1_mean']:.3f}"
            print(
                f"  {label:<14} success {m['success_rate']:.2f} ({m['runs']} runs), "
                f"planning {t:.3f} ± {sd:.3f} s{f1}, crashed {m['crashed']}"
            )
    total, target = float(res["total_wall_time_s"]), TARGETS_S[g]  # type: ignore[arg-type]
    verdict = "within" if total <= target else "OVER"
    print(f"total {total:.1f} s ({verdict} the {target:.0f} s target)")
    cpu, workers = float(res["cpu_time_s"]), int(res["workers"])  # type: ignore[call-overload]
    print(
        f"CPU time {cpu:.1f} s (~{cpu / max(workers, 1):.1f} s of wall time on {workers} idle "
        f"core(s)); load average at the end {res['load_average']}"
    )


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grounding", choices=("symbolic", "physics", "both"), default="symbolic")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--limit", type=int, help="only the first N scenes per suite")
    ap.add_argument("--keep", help="write the sweep outputs here (must not hold results yet)")
    ap.add_argument("--json", help="also write the measurements here")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    groundings = ("symbolic", "physics") if args.grounding == "both" else (args.grounding,)
    with tempfile.TemporaryDirectory(prefix="utamp_eval_bench_") as tmp:
        root = Path(args.keep or tmp)
        if any(root.glob("*/*/results.csv")):
            raise SystemExit(f"{root} already holds results: the sweep would resume, not run")
        results = [_sweep(g, args, root) for g in groundings]
    for res in results:
        _print(res)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
