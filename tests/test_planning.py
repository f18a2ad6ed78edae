"""Planning: every suite scene solved by UTAMP-2-GT with valid plans; methods; bad input."""

from __future__ import annotations

import pytest
import wide
from procs import downward_children

from utamp_gym.deadline import Deadline
from utamp_gym.errors import PlanningTimeout, UnknownNameError
from utamp_gym.planning import fast_downward
from utamp_gym.planning.crosscheck import affordance_violations, check_against_ground_truth
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene import scene_from_dict
from utamp_gym.suites import resolve_scene, suite_scenes
from utamp_gym.symbolic.pddl import parse_domain, parse_plan, parse_problem
from utamp_gym.symbolic.validate import validate_plan


@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_utamp2_gt_solves_every_scene_with_valid_plans(suite: str) -> None:
    for scene in suite_scenes(suite):
        out = plan_scene(scene, "utamp2-gt", timeout=60)
        assert out.solved, (scene.name, out.reason)
        result = validate_plan(
            parse_domain(out.domain), parse_problem(out.problem), parse_plan("\n".join(out.plan))
        )
        assert result.valid, (scene.name, result.message)
        assert check_against_ground_truth(scene, out.plan).valid
        if suite == "sliding":  # the tray is slid in before anything is put on it
            slide = next(i for i, a in enumerate(out.plan) if a.startswith("(slide-support tray "))
            onto_tray = [
                i
                for i, a in enumerate(out.plan)
                if a.startswith("(place-support") and " tray " in a
            ]
            assert onto_tray and slide < onto_tray[0]


def test_both_translators_give_valid_plans() -> None:
    scene = resolve_scene("kitchen-demo")
    out = plan_scene(scene)
    for translator in fast_downward.TRANSLATORS:
        res = fast_downward.solve(out.domain, out.problem, translator=translator)
        assert res.solved
        check = validate_plan(
            parse_domain(out.domain), parse_problem(out.problem), parse_plan("\n".join(res.plan))
        )
        assert check.valid, (translator, check.message)


def test_rules_match_gt_and_noise_is_seeded() -> None:
    scene = suite_scenes("pick-place")[-1]
    gt, rules = plan_scene(scene, "utamp2-gt"), plan_scene(scene, "utamp2-rules")
    assert rules.facts == gt.facts and rules.affordance_scores.f1 == 1.0
    a = plan_scene(scene, "utamp2-noisy", seed=4, noise=0.2)
    b = plan_scene(scene, "utamp2-noisy", seed=4, noise=0.2)
    assert a.facts == b.facts and a.plan == b.plan
    assert a.affordance_scores.f1 < 1.0


def test_noisy_detection_differs_between_scenes_of_one_seed() -> None:
    """One seed must not repeat one corruption in every scene of a sweep."""
    scene = resolve_scene("kitchen-demo")
    twin = scene._replace(name="kitchen-demo-twin")  # same objects, other name
    pairs = [
        (
            plan_scene(scene, "utamp2-noisy", seed=s, noise=0.2).facts,
            plan_scene(twin, "utamp2-noisy", seed=s, noise=0.2).facts,
        )
        for s in range(3)
    ]
    assert any(a != b for a, b in pairs)


def test_utamp1_plans_violate_ground_truth_where_they_ignore_affordances() -> None:
    scene = resolve_scene("kitchen-demo")
    out = plan_scene(scene, "utamp1", timeout=60)
    assert out.solved
    check = check_against_ground_truth(scene, out.plan)
    assert not check.valid
    assert check.failed_precondition is not None
    assert any(
        p in check.failed_precondition
        for p in ("canGraspFrom", "canLift", "isSupportive", "isSupportable", "isP2PSupportive")
    )


def test_unsolvable_scene_is_reported_not_raised(demo_dict) -> None:
    # pan and upright mug: nothing can stand on the pan but the board, the mug carries nothing
    demo_dict["objects"] = [o for o in demo_dict["objects"] if o["name"] in ("tray", "pan", "mug")]
    demo_dict["objects"][2]["orientation"] = "upright"
    out = plan_scene(scene_from_dict(demo_dict), "utamp2-gt")
    assert not out.solved and out.plan == ()
    assert "unsolvable" in out.reason


def test_timeout_is_reported_and_no_planner_survives() -> None:
    scene = suite_scenes("pick-place")[-1]
    # a limit over before the call (deterministic; any phase may run out on a real machine)
    out = plan_scene(scene, "utamp1", deadline=Deadline.after(1e-9))
    assert out.timed_out and not out.solved and "timed out" in out.reason
    assert out.domain and out.problem  # the task is still reported
    with pytest.raises(PlanningTimeout) as info:  # grounding takes minutes: tests/wide.py
        fast_downward.solve(wide.DOMAIN, wide.problem(), timeout=0.05)
    assert info.value.phase == "grounding" and downward_children() == []


def test_unknown_method_lists_valid_ones() -> None:
    valid = "valid: utamp1, utamp2-gt, utamp2-noisy, utamp2-perceived, utamp2-rules"
    with pytest.raises(UnknownNameError, match=valid):
        plan_scene(resolve_scene("kitchen-demo"), "magic")


def test_affordance_violations_lists_every_step_that_ignores_the_ground_truth() -> None:
    scene = resolve_scene("kitchen-demo")
    gt = plan_scene(scene, "utamp2-gt")
    assert affordance_violations(scene, gt.plan) == []
    backwards = [gt.plan[1], gt.plan[0]]  # invalid by state (place first), not by affordance
    assert affordance_violations(scene, backwards) == []
    u1 = plan_scene(scene, "utamp1", timeout=60)
    bad = affordance_violations(scene, u1.plan)
    first = check_against_ground_truth(scene, u1.plan)
    assert bad and bad[0] == (first.failing_step - 1, first.failed_precondition)
    body = "(pick-support board board-body on left right back on slot3 under on)"
    assert affordance_violations(scene, [gt.plan[0], body]) == [
        (1, "(canGraspFrom board board-body on left right)")
    ]


@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_our_grounder_and_fd_translator_plan_equally_long(suite: str) -> None:
    """A sample of the suite (benchmarks/planning.py --sections crosscheck runs all of it)."""
    cases = [(scene, "utamp2-gt") for scene in suite_scenes(suite)[::9]]
    if suite == "pick-place":
        cases += [(suite_scenes(suite)[0], "utamp1")]
    for scene, method in cases:
        ours = plan_scene(scene, method, timeout=120)
        theirs = fast_downward.solve(ours.domain, ours.problem, translator="fd", timeout=120)
        assert ours.solved and theirs.solved, scene.name
        assert ours.plan_length == len(theirs.plan), (scene.name, method)
