"""Physics sweep: UTAMP-2-GT plans executed in MuJoCo on every suite scene, over seeds.

Prints success per suite and object count, the failure reasons, and the median macro-step
and episode wall times (targets: ≤ 0.5 s per step, ≤ 5 s per five-object episode).

For plans that violate the ground-truth affordances (``--method utamp1``), it also
compares where physics failed with the first violating step
(`check_against_ground_truth`): at that step, earlier, later, or not at all.

    python benchmarks/physics_suite.py [--seeds 3] [--stride 1] [--suites pick-place,sliding]
                                       [--method utamp2-gt|utamp1|...]
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics

os.environ.setdefault("MUJOCO_GL", "egl")

from utamp_gym.planning.crosscheck import check_against_ground_truth
from utamp_gym.sim.execute import EpisodeResult, run_episode
from utamp_gym.suites import suite_scenes


def agreement(scene, r: EpisodeResult) -> str:
    """Where physics failed relative to the plan's first ground-truth violation."""
    check = check_against_ground_truth(scene, r.plan)
    violated = None if check.valid else (check.failing_step or len(r.plan) + 1) - 1  # 0-based
    failed = None if r.success else r.failure["step"]
    if violated is None:
        return "no violation, physics succeeded" if r.success else "no violation, physics failed"
    if failed is None:
        return "violation, physics succeeded"
    if failed == violated:
        return "violation, physics failed at that step"
    return f"violation, physics failed {'earlier' if failed < violated else 'later'}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suites", default="pick-place,sliding")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--stride", type=int, default=1, help="use every k-th scene")
    ap.add_argument("--method", default="utamp2-gt")
    args = ap.parse_args()

    table: dict[tuple[str, int], list[bool]] = collections.defaultdict(list)
    reasons: collections.Counter[str] = collections.Counter()
    step_times: list[float] = []
    episode_times: dict[int, list[float]] = collections.defaultdict(list)
    agree: collections.Counter[str] = collections.Counter()
    unexpected: list[str] = []
    for suite in args.suites.split(","):
        for scene in suite_scenes(suite)[:: args.stride]:
            for seed in range(args.seeds):
                r = run_episode(scene, args.method, seed=seed)
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
    print("\n## Physical failure vs first ground-truth violation (solved plans)")
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
