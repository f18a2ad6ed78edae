"""Physics sweep: UTAMP-2-GT plans executed in MuJoCo on every suite scene, over seeds.

Prints success per suite and object count, the failure reasons, and the median macro-step
and episode wall times (targets: ≤ 0.5 s per step, ≤ 5 s per five-object episode).

For plans that ignore ground-truth affordances (``--method utamp1``), it also matches
where physics failed with the steps that violate them (`affordance_violations`): at a
violating step, at the place completing a violating pick, elsewhere, or not at all.

    python benchmarks/physics_suite.py [--seeds 3] [--stride 1] [--suites pick-place,sliding]
                                       [--method utamp2-gt|utamp1|...]
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics

os.environ.setdefault("MUJOCO_GL", "egl")

from utamp_gym.planning.crosscheck import affordance_violations
from utamp_gym.scene.model import Scene
from utamp_gym.sim.execute import EpisodeResult, run_episode
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
