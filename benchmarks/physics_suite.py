"""Physics sweep: UTAMP-2-GT plans executed in MuJoCo on every suite scene, over seeds.

Prints success per suite and object count, the failure reasons, and the median macro-step
and episode wall times (targets: ≤ 0.5 s per step, ≤ 5 s per five-object episode).

    python benchmarks/physics_suite.py [--seeds 3] [--stride 1] [--suites pick-place,sliding]
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics

os.environ.setdefault("MUJOCO_GL", "egl")

from utamp_gym.sim.execute import run_episode
from utamp_gym.suites import suite_scenes


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
    for suite in args.suites.split(","):
        for scene in suite_scenes(suite)[:: args.stride]:
            for seed in range(args.seeds):
                r = run_episode(scene, args.method, seed=seed)
                table[(suite, scene.n_objects)].append(r.success)
                episode_times[scene.n_objects].append(r.wall_time_s)
                step_times += [s.timings.get("wall_s", 0.0) for s in r.steps]
                if r.failure:
                    reasons[str(r.failure["reason"]).split(":")[0]] += 1
                print(f"{scene.name} seed {seed}: {'ok' if r.success else r.failure}", flush=True)

    print(f"\n## Physics success, {args.method}, {args.seeds} seed(s)")
    print("| suite | n | episodes | success |\n|---|---|---|---|")
    for (suite, n), ok in sorted(table.items()):
        print(f"| {suite} | {n} | {len(ok)} | {sum(ok) / len(ok):.2f} |")
    print("\n## Failure reasons")
    for reason, count in reasons.most_common() or [("none", 0)]:
        print(f"- {reason}: {count}")
    if step_times:
        print(f"\nmedian macro step {statistics.median(step_times):.3f} s wall (target 0.5 s)")
    for n, ts in sorted(episode_times.items()):
        print(f"n={n}: median episode {statistics.median(ts):.2f} s, max {max(ts):.2f} s")


if __name__ == "__main__":
    main()
