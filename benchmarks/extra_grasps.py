"""Every derived grasp of the objects beyond the paper, executed in physics.

For each two-object scene of the `extra` suite (the tray and one new object in another
slot) and each grasp the rule parser derives for that object with the palm on its
up-facing part, plan with only that grasp allowed (Fast Downward) and execute the
plan in MuJoCo: pick the object by that member, place it on the tray. The planner
alone picks one grasp per object; this exercises all of them.

    python benchmarks/extra_grasps.py [--seeds 3]
"""

from __future__ import annotations

import argparse

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.sources import ground_truth_for
from utamp_gym.agents.runs import execute_plan
from utamp_gym.planning.fast_downward import solve
from utamp_gym.scene.model import UP_PART, Scene
from utamp_gym.suites import suite_scenes
from utamp_gym.symbolic.problem import build_problem, domain_text


def grasp_cases() -> list[tuple[Scene, str, Fact]]:
    """(scene, object, grasp fact) for every top-down grasp of each lone new object."""
    out = []
    for scene in suite_scenes("extra"):
        if scene.n_objects != 2:
            continue
        obj = next(o for o in scene.objects if o.name != "tray")
        facts = ground_truth_for(scene)
        up = UP_PART[obj.orientation]
        for f in sorted(facts):
            if f[0] == "canGraspFrom" and f[1] == obj.type and f[3] == up:
                out.append((scene, obj.name, f))
    return out


def plan_with_grasp(scene: Scene, obj: str, grasp: Fact) -> tuple[str, ...]:
    """An optimal plan in which the object may only be grasped by `grasp`."""
    t = scene.type_of(obj).name
    facts = {f for f in ground_truth_for(scene) if f[:2] != ("canGraspFrom", t) or f == grasp}
    result = solve(domain_text("utamp2"), build_problem(scene, facts).text)
    if not result.solved:
        raise RuntimeError(f"{scene.name}: no plan with {grasp}: {result.reason}")
    return result.plan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    print("| object | grasp (member, palm, fingers) | success | failures |\n|---|---|---|---|")
    for scene, obj, grasp in grasp_cases():
        plan = plan_with_grasp(scene, obj, grasp)
        runs = [execute_plan(scene, plan, seed=s) for s in range(args.seeds)]
        ok = sum(r.success for r in runs)
        why = "; ".join(sorted({r.failure_reason for r in runs if not r.success}))
        label = f"{grasp[1]}{' (inverted)' if grasp[3] == 'under' else ''}"
        print(f"| {label} | {', '.join(grasp[2:])} | {ok}/{len(runs)} | {why} |", flush=True)


if __name__ == "__main__":
    main()
