"""Physics sweep: UTAMP-2-GT plans executed in MuJoCo on every suite scene, over seeds.

Prints success per suite and object count, the failure reasons, and the median macro-step
and episode wall times (targets: ≤ 0.5 s per step, ≤ 5 s per five-object episode).

For plans that ignore ground-truth affordances (``--method utamp1``), it also matches
where physics failed with the steps that violate them (`affordance_violations`): at a
violating step, at the place completing a violating pick, elsewhere, or not at all.

    python benchmarks/physics_suite.py [--seeds 3] [--stride 1] [--suites pick-place,sliding]
                                       [--method utamp2-gt|utamp1|...] [--noise-m M]

With ``--pose-noise`` it instead sweeps the robot's pose-estimation noise (0, 2, 5, 10 mm;
`--seeds` seeds at the default noise, 1 elsewhere) through the evaluation harness
(`--workers` processes, rows in `--out`, resumable) and prints success per suite and noise,
the failure reasons per noise level, and writes ``success_vs_pose_noise.png``.
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import save_success_plot

from utamp_gym.agents.runs import EpisodeResult, run_episode
from utamp_gym.backend import DEFAULT_POSE_NOISE
from utamp_gym.planning.crosscheck import affordance_violations
from utamp_gym.provenance import commit, write_markdown
from utamp_gym.scene.model import Scene
from utamp_gym.suites import suite_scenes


def agreement(scene: Scene, r: EpisodeResult) -> str:
    """Where physics failed relative to the steps that ignore ground-truth affordances."""
    bad = dict(affordance_violations(scene, r.plan))
    failed = None if r.success else r.failure["step"]
    if not bad:
        return "no violation, physics " + ("succeeded" if r.success else "failed")
    if failed is None:
        return "violation, physics succeeded"
    if failed in bad:
        return "violation, physics failed at a violating step"
    if failed - 1 in bad and failed < len(r.plan):
        prev, now = r.plan[failed - 1].split(), r.plan[failed].split()
        if prev[0] == "(pick-support" and now[1] == prev[1]:
            return "violation, physics failed placing the object a violating pick took"
    return "violation, physics failed at a step without violation"


NOISE_LEVELS = (0.0, 0.002, 0.005, 0.010)  # m


def noise_sweep(args: argparse.Namespace) -> None:
    """Success vs pose-estimation noise, through the evaluation harness."""
    from utamp_gym.eval.sweep import SweepConfig, run_sweep

    out = Path(args.out)
    levels = (
        NOISE_LEVELS if args.levels is None else tuple(float(v) for v in args.levels.split(","))
    )
    table: dict[tuple[str, float], list[bool]] = collections.defaultdict(list)
    reasons: dict[float, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    for suite in args.suites.split(","):
        for noise in levels:
            seeds = args.seeds if noise == DEFAULT_POSE_NOISE else 1
            cfg = SweepConfig(
                suite, (args.method,), seeds=seeds, pose_noise=noise, explain=False,
                limit=args.limit,
            )  # fmt: skip
            report = run_sweep(cfg, out / suite, workers=args.workers, progress=False)
            for r in report.rows:
                table[(suite, noise)].append(r.success)
                if not r.success:
                    reasons[noise][_reason(r.failure_reason)] += 1
            ok = table[(suite, noise)]
            print(f"{suite} noise {noise * 1000:g} mm: {sum(ok)}/{len(ok)}", flush=True)
    lines = [
        f"## Physics success vs pose-estimation noise, {args.method} (with the wrist re-look)",
        "",
        "| suite | noise (mm) | seeds | episodes | success |",
        "|---|---|---|---|---|",
    ]
    for (suite, noise), ok in sorted(table.items()):
        seeds = args.seeds if noise == DEFAULT_POSE_NOISE else 1
        lines.append(
            f"| {suite} | {noise * 1000:g} | {seeds} | {len(ok)} | {sum(ok)}/{len(ok)} "
            f"({sum(ok) / len(ok):.3f}) |"
        )
    for noise, counts in sorted(reasons.items()):
        lines += ["", f"Failures at {noise * 1000:g} mm:", ""]
        lines += [f"* {reason}: {count}" for reason, count in counts.most_common()]
    print("\n" + "\n".join(lines))
    if args.results is not None:
        args.results.mkdir(parents=True, exist_ok=True)
        path = args.results / "pose_noise_relook.md"
        write_markdown(path, "\n".join(lines) + "\n")
        print(f"wrote {path}")
    _plot_noise(table, out / "success_vs_pose_noise.png")


def _reason(failure: str) -> str:
    """A failure reason without its step and numbers (to count kinds)."""
    text = failure.split(": ", 1)[-1] if failure.startswith("step ") else failure
    return text.split(" (")[0]


def _plot_noise(table: dict[tuple[str, float], list[bool]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.0, 3.4))
    for suite in sorted({s for s, _ in table}):
        noises = sorted(n for s, n in table if s == suite)
        rates = [sum(table[(suite, n)]) / len(table[(suite, n)]) for n in noises]
        ax.plot([1000 * n for n in noises], rates, "-o", label=suite)
    ax.axvline(1000 * DEFAULT_POSE_NOISE, color="grey", lw=0.8, ls=":", label="default")
    ax.set_xlabel("pose-estimation noise (mm, std per axis)")
    save_success_plot(fig, ax, path, "UTAMP-2-GT in physics vs pose-estimation noise")
    print(f"\nwrote {path}")


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suites", default="pick-place,sliding")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--stride", type=int, default=1, help="use every k-th scene")
    ap.add_argument("--method", default="utamp2-gt")
    ap.add_argument("--noise-m", type=float, default=DEFAULT_POSE_NOISE, help="pose noise (m)")
    ap.add_argument("--pose-noise", action="store_true", help="sweep the pose noise instead")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--limit", type=int, default=None, help="noise sweep: first N scenes")
    ap.add_argument("--out", default="out/bench/pose_noise", help="noise sweep: rows here")
    ap.add_argument("--levels", help="noise sweep: these levels (m, comma-separated)")
    ap.add_argument("--results", type=Path, help="noise sweep: also write the table here")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    if args.pose_noise:
        noise_sweep(args)
        return

    table: dict[tuple[str, int], list[bool]] = collections.defaultdict(list)
    reasons: collections.Counter[str] = collections.Counter()
    step_times: list[float] = []
    episode_times: dict[int, list[float]] = collections.defaultdict(list)
    agree: collections.Counter[str] = collections.Counter()
    unexpected: list[str] = []
    for suite in args.suites.split(","):
        for scene in suite_scenes(suite)[:: args.stride]:
            for seed in range(args.seeds):
                r = run_episode(scene, args.method, seed=seed, pose_noise=args.noise_m)
                table[(suite, scene.n_objects)].append(r.success)
                episode_times[scene.n_objects].append(r.wall_time_s)
                step_times += [s.timings.get("wall_s", 0.0) for s in r.steps]
                if r.failure:
                    reasons[str(r.failure["reason"]).split(":")[0]] += 1
                if r.solved:
                    how = agreement(scene, r)
                    agree[how] += 1
                    if how.startswith("violation, physics succeeded"):
                        unexpected.append(f"{scene.name} seed {seed}")
                print(f"{scene.name} seed {seed}: {'ok' if r.success else r.failure}", flush=True)

    print(f"\n## Physics success, {args.method}, {args.seeds} seed(s)")
    print("| suite | n | episodes | success |\n|---|---|---|---|")
    for (suite, n), ok in sorted(table.items()):
        print(f"| {suite} | {n} | {len(ok)} | {sum(ok) / len(ok):.2f} |")
    print("\n## Failure reasons")
    for reason, count in reasons.most_common() or [("none", 0)]:
        print(f"- {reason}: {count}")
    print("\n## Physical failure vs ground-truth affordance violations (solved plans)")
    for how, count in sorted(agree.items()):
        print(f"- {how}: {count}")
    for name in unexpected:
        print(f"  - succeeded despite a violation: {name}")
    if step_times:
        print(f"\nmedian macro step {statistics.median(step_times):.3f} s wall (target 0.5 s)")
    for n, ts in sorted(episode_times.items()):
        print(f"n={n}: median episode {statistics.median(ts):.2f} s, max {max(ts):.2f} s")


if __name__ == "__main__":
    main()
