"""Closed loop vs open loop under injected faults (UTAMP-2-GT, physics).

For every suite and fault probability p (``--levels``), the same scenes and seeds run
open-loop (the paper's protocol: plan once, execute, stop at the first failure) and
closed-loop (`utamp eval --closed-loop`: the planner policy perceives and replans). Prints
per (suite, p): open-loop success, closed-loop success, recovery rate (closed-loop episodes
with at least one fault that still reached the goal), mean replans and wall time per
episode; then the happy path's cost (p = 0): perception per step and the median episode
execution time open-loop vs closed-loop, measured side by side in this run. Writes
``success_vs_disturbance.png`` next to the rows (``--out``, resumable).

    python benchmarks/closed_loop.py [--suites pick-place,sliding] [--levels 0,0.05,0.1,0.2]
        [--seeds 1] [--limit N] [--workers 2] [--out out/bench/closed_loop]
        [--perception gaussian|rgbd] [--results docs/results]

``--perception rgbd``: the robot's object poses (for decoding actions, and the closed loop's
perceived state) come from the rendered cameras instead of the Gaussian stand-in (targets:
closed loop >= 0.98 at p = 0 and >= 0.97 at p = 0.1 on pick-place). With ``--results`` the
table is also written to ``closed_loop_<perception>.md`` there.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import save_success_plot

from utamp_gym.eval.records import ResultRow
from utamp_gym.eval.sweep import SweepConfig, run_sweep
from utamp_gym.provenance import commit, write_markdown
from utamp_gym.suites import suite_scenes

TARGET = 0.95  # closed-loop success at p = 0.1 on pick-place (Gaussian stand-in)
#: perception="rgbd" targets on pick-place: closed-loop success per fault probability
RGBD_TARGETS = {0.0: 0.98, 0.1: 0.97}


def perception_cost(scenes: list[str], seed: int = 0) -> list[float]:
    """Seconds per step spent perceiving, over closed-loop episodes of `scenes` at p = 0."""
    from utamp_gym.agents import PlannerPolicy
    from utamp_gym.env.kitchen import UTampKitchenEnv

    out: list[float] = []
    for name in scenes:
        env = UTampKitchenEnv(suite=name.split("/")[0], scene=name, record_timings=True)
        policy = PlannerPolicy(env)
        obs, info = env.reset(seed=seed)
        for _ in range(40):
            obs, _, terminated, truncated, info = env.step(policy(obs, info))
            out.append(info["timings"]["perceive_s"])
            if terminated or truncated:
                break
        env.close()
    return out


def summarise(rows: list[ResultRow], levels: list[float]) -> dict[tuple[str, float], dict]:
    table = {}
    for suite in sorted({r.suite for r in rows}):
        for p in levels:
            sel = [r for r in rows if r.suite == suite and r.disturbance == p]
            closed = [r for r in sel if r.closed_loop]
            opened = [r for r in sel if not r.closed_loop]
            faulty = [r for r in closed if r.n_faults > 0]
            if not closed:
                continue
            table[(suite, p)] = {
                "n": len(closed),
                "open": sum(r.success for r in opened) / len(opened) if opened else float("nan"),
                "closed": sum(r.success for r in closed) / len(closed),
                "faulty": len(faulty),
                "recovery": sum(r.success for r in faulty) / len(faulty) if faulty else None,
                "replans": statistics.mean(r.n_replans for r in closed),
                "wall_open": statistics.mean(r.wall_time_s for r in opened) if opened else 0.0,
                "wall_closed": statistics.mean(r.wall_time_s for r in closed),
            }
    return table


def plot(table: dict[tuple[str, float], dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for suite in sorted({s for s, _ in table}):
        ps = sorted(p for s, p in table if s == suite)
        for mode, style in (("closed", "-o"), ("open", "--s")):
            ax.plot(ps, [table[(suite, p)][mode] for p in ps], style, label=f"{suite}, {mode} loop")
    ax.axhline(TARGET, color="grey", lw=0.8, ls=":")
    ax.set_xlabel("fault probability per macro action")
    save_success_plot(fig, ax, path, "UTAMP-2-GT in physics under injected faults")


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suites", default="pick-place,sliding")
    ap.add_argument("--levels", default="0,0.05,0.1,0.2")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--limit", type=int, default=None, help="only the first N scenes per suite")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default="out/bench/closed_loop")
    ap.add_argument("--perception", choices=("gaussian", "rgbd"), default="gaussian")
    ap.add_argument("--results", type=Path, help="also write the table here (markdown)")
    ap.add_argument("--skip-cost", action="store_true", help="skip the per-step cost sample")
    ap.add_argument("--modes", default="open,closed", help="open,closed (default) or one of them")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    levels = [float(p) for p in args.levels.split(",")]
    out = Path(args.out) / args.perception
    rows: list[ResultRow] = []
    start = time.perf_counter()
    for suite in args.suites.split(","):
        for p in levels:
            for closed in [m == "closed" for m in args.modes.split(",")]:
                cfg = SweepConfig(
                    suite,
                    ("utamp2-gt",),
                    seeds=args.seeds,
                    disturbance=p,
                    closed_loop=closed,
                    explain=False,
                    limit=args.limit,
                    perception=args.perception,
                )
                report = run_sweep(cfg, out / suite, workers=args.workers, progress=False)
                rows += report.rows
                print(
                    f"{suite} p={p:g} {'closed' if closed else 'open'}: "
                    f"{sum(r.success for r in report.rows)}/{len(report.rows)}",
                    flush=True,
                )
    table = summarise(rows, levels)
    lines = [
        f"UTAMP-2-GT in physics, perception `{args.perception}`, {args.seeds} seed(s), "
        f"`benchmarks/closed_loop.py --perception {args.perception}`.",
        "",
        "| suite | p | n | open-loop | closed-loop | recovery (faulty eps) | replans |"
        " wall/ep open | wall/ep closed |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for (suite, p), t in sorted(table.items()):
        rec = "–" if t["recovery"] is None else f"{t['recovery']:.2f} ({t['faulty']})"
        closed_n = round(t["closed"] * t["n"])
        ran_open = not math.isnan(t["open"])  # NaN: the open loop was not run (--modes closed)
        opened = f"{t['open']:.2f}" if ran_open else "–"
        wall_open = f"{t['wall_open']:.2f} s" if ran_open else "–"
        lines.append(
            f"| {suite} | {p:g} | {t['n']} | {opened} | {t['closed']:.3f} ({closed_n}) | "
            f"{rec} | {t['replans']:.2f} | {wall_open} | {t['wall_closed']:.2f} s |"
        )
    targets = RGBD_TARGETS if args.perception == "rgbd" else {0.1: TARGET}
    lines.append("")
    for p, target in targets.items():
        hit = table.get(("pick-place", p))
        if hit:
            verdict = "met" if hit["closed"] >= target else "NOT met"
            lines.append(
                f"* target closed-loop >= {target:.2f} at p = {p:g} on pick-place: "
                f"{hit['closed']:.3f} ({verdict})"
            )
    failures = [r for r in rows if r.closed_loop and not r.success]
    if failures:
        lines += ["", "Closed-loop failures:", ""]
        lines += [f"* {r.scene} p={r.disturbance:g}: {r.failure_reason[:240]}" for r in failures]
    print("\n" + "\n".join(lines))
    if args.results is not None:
        args.results.mkdir(parents=True, exist_ok=True)
        path = args.results / f"closed_loop_{args.perception}.md"
        write_markdown(path, "\n".join(lines) + "\n")
        print(f"wrote {path}")
    happy = [r for r in rows if r.disturbance == 0.0]
    for mode in (False, True):
        ex = [r.execution_time_s for r in happy if r.closed_loop == mode]
        if ex:
            print(
                f"p = 0, {'closed' if mode else 'open'} loop: median episode execution "
                f"{statistics.median(ex):.3f} s over {len(ex)} episodes"
            )
    opened = [r.execution_time_s for r in happy if not r.closed_loop]
    closed = [r.execution_time_s for r in happy if r.closed_loop]
    if opened and closed:
        ratio = statistics.median(closed) / statistics.median(opened)
        print(f"closed/open median execution ratio at p = 0: {ratio:.3f} (target <= 1.10)")
    if args.skip_cost:
        plot(table, out / "success_vs_disturbance.png")
        return
    sample = [s.name for s in suite_scenes("pick-place")[::15]]
    cost = perception_cost(sample)
    cost.sort()
    print(
        f"perception per step: median {1000 * statistics.median(cost):.2f} ms, "
        f"p95 {1000 * cost[int(0.95 * (len(cost) - 1))]:.2f} ms over {len(cost)} steps "
        "(target <= 5 ms)"
    )
    plot(table, out / "success_vs_disturbance.png")
    print(f"\nwrote {out / 'success_vs_disturbance.png'}; {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
