"""Interactive perception in the closed loop (eval/interactive.py): beliefs revised by weighing,
topples and extra looks; counts reported per episode."""

from __future__ import annotations

from pathlib import Path

import pytest

from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.errors import PlanningError
from utamp_gym.eval import interactive
from utamp_gym.eval.closed_loop import NO_ACTIONS, run_closed_loop
from utamp_gym.eval.interactive import SATURATED_MASS, InteractivePerception
from utamp_gym.seeding import run_seed

SCENE = "pick-place/000"  # a board on a tray: the tower's one support


@pytest.fixture
def loop():
    env = UTampKitchenEnv(suite="pick-place", scene=SCENE, grounding="symbolic", affordances="gt")
    world = run_seed(SCENE, 0)
    obs, info = env.reset(seed=world, options={"world_seed": world})
    policy = PlannerPolicy(env, "utamp2-perceived")
    ip = InteractivePerception(policy, env)
    ip(obs, info)  # the first decision: look, believe, plan
    yield ip, obs, info
    env.close()


def _believed(ip: InteractivePerception) -> frozenset:
    return ip.policy._facts[SCENE]


def test_first_look_believes_the_perceived_affordances(loop) -> None:
    ip, _, _ = loop
    # the calibrated confidences leave the tray's and the board's mass in doubt: the cautious
    # (heavier) masses leave no plan, so one look plans those doubts at their likely values
    assert ip.n_weighings == 0 and ip.n_looks == 1
    assert ip.revisions == ["look 1 (likely): no plan; doubts: tray.mass, board.mass"]
    assert ("canLift", "cutting-board", "handle") in _believed(ip)
    assert set(ip.beliefs) == {"tray", "board"}


def test_a_payload_refusal_weighs_the_object(loop) -> None:
    ip, _, _ = loop
    ip._revise(
        "board exceeds the Panda's 3 kg payload while lifting it: the joint torques measure "
        "3.4 kg (33 N) at the hand"
    )
    assert ip.n_weighings == 1 and ip.beliefs["board"].mass == pytest.approx(3.4)
    assert not any(f[0] == "canLift" and f[1] == "cutting-board" for f in _believed(ip))
    ip._revise(
        "board exceeds the Panda's payload while lifting it: the torque of joint 4 at its "
        "87 N·m limit cannot hold it (measured load at least 2.1 kg (21 N))"
    )  # saturated: a lower bound, at least SATURATED_MASS
    assert ip.n_weighings == 2 and ip.beliefs["board"].mass == pytest.approx(SATURATED_MASS)


def test_a_lift_that_stays_down_withdraws_that_members_lift(loop) -> None:
    ip, _, _ = loop
    ip._revise("board is not liftable by its handle: it stayed down (rose 0.1 cm while ...)")
    assert ip.n_weighings == 1
    assert ("canLift", "cutting-board", "handle") not in _believed(ip)


def test_a_topple_marks_the_support_and_an_unsolvable_goal_triggers_looks(loop) -> None:
    ip, obs, info = loop
    ip._revise("board tipped over on tray")
    assert not any(
        f[0] == "isP2PSupportive" and (f[2], f[4]) == ("wooden-tray", "cutting-board")
        for f in _believed(ip)
    )
    assert ip.revisions[-1] == "board does not stand on tray"
    # the board has no other way onto the tray: the episode's looks run out (the first was
    # taken at the start, see above), then the policy gives up
    with pytest.raises(PlanningError):
        ip(obs, {**info, "action": "(noop)", "failure_reason": "board tipped over on tray"})
    assert ip.n_looks == 2
    # (two objects' size readings together allow nothing one alone does not: no second stage)
    assert ip.revisions[-1].split(":")[0] == "look 2 (hopeful)"


def test_the_hopeful_look_hopes_for_one_misreading_before_two(
    loop, monkeypatch: pytest.MonkeyPatch
) -> None:
    """As the open loop: the facts two objects' size readings allow only once those one
    object's alternative allows leave no plan, without another survey."""
    ip, _, _ = loop
    pair_only = ("canLift", "tray-seen", "body")  # in the perceived types' names
    calls = []

    def hoped(planning, types, reports, *, pairs=True, **kw):  # type: ignore[no-untyped-def]
        calls.append(pairs)
        return frozenset({pair_only}) if pairs else frozenset()

    monkeypatch.setattr(interactive, "hoped_facts", hoped)
    ip._look("hopeful")
    assert ip.hoping == 1 and calls[-1] is False
    singles, looks = _believed(ip), ip.n_looks
    assert ip._look_at_blockers()
    assert ip.hoping == 2 and ip.n_looks == looks and calls[-1] is True
    (added,) = _believed(ip) - singles
    assert added[:2] == ("canLift", "wooden-tray")
    assert ip.revisions[-1] == "no plan: hoping for two objects' size readings too"


def test_a_pick_of_a_hypothesised_mass_counts_as_weighing(loop) -> None:
    ip, _, _ = loop
    ip.untested = {"board"}
    ip._lifted("(pick-support board board-handle on left right back on slot2 under on)")
    ip._lifted("(pick-support board board-handle on left right back on slot2 under on)")
    assert ip.n_weighings == 1 and ip.untested == set()


def test_closed_loop_reports_weighings_and_looks() -> None:
    out = run_closed_loop(SCENE, "utamp2-perceived", grounding="physics", pose_noise=0.0)
    assert out.success, out.failure
    # nothing failed: no weighing; one look plans the mass doubts at their likely values
    assert (out.n_weighings, out.n_looks) == (0, 1)
    named = run_closed_loop(SCENE, "utamp2-perceived:builtin", grounding="symbolic")
    assert named.success and named.n_looks == 1


def test_a_perceiver_that_sees_nothing_ends_the_episode_at_perception(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    out = run_closed_loop(
        SCENE, "utamp2-perceived:user_perceiver:BlindPerceiver", grounding="symbolic"
    )
    assert not out.success and out.failure.startswith("perception: no camera saw")


@pytest.mark.parametrize("grounding", ["symbolic", "physics"])
def test_a_scene_that_affords_no_action_ends_unsolved_not_crashed(grounding: str) -> None:
    # procedural-v1/train/0040: two objects whose ground-truth affordances leave no ground
    # action in the scene's own universe (the env's Discrete(0) used to raise ValueError)
    out = run_closed_loop("procedural-v1/train/0040", "utamp2-perceived", grounding=grounding)
    assert not out.success and out.actions == ()
    assert out.failure.endswith(NO_ACTIONS) and out.failure.startswith("no plan")


@pytest.mark.parametrize(
    "reason",
    [
        "precondition (canLift cutting-board handle) of (pick-support board board-handle on "
        "left right back on slot2 under on) is false (static)",  # the env's precondition check
        "canLift(cutting-board, handle) is false (ground truth)",  # symbolic outcome model
    ],
)
def test_a_refused_affordance_is_withdrawn(loop, reason: str) -> None:
    ip, _, _ = loop
    assert ("canLift", "cutting-board", "handle") in _believed(ip)
    ip._revise(reason)
    assert ("canLift", "cutting-board", "handle") not in _believed(ip)
    assert ip.revisions[-1] == "refused: canLift(cutting-board, handle) withdrawn"
    ip._revise(reason)  # withdrawn once
    assert ip.revisions.count(ip.revisions[-1]) == 1


def test_the_last_look_hopes_within_the_reading_error_and_the_acts_confirm_it() -> None:
    """A tumbler read 0.1-0.3 mm wider than its 7.4 cm leaves no grasp in the rules; its
    narrower reading does, and the hand then lifts it (train scene, never fitted)."""
    out = run_closed_loop("procedural-v1/train/0191", "utamp2-perceived", grounding="symbolic")
    assert out.success, out.failure
    assert out.n_looks == 2 and out.n_weighings == 0  # likely values, then hoping


def test_the_lightest_plausible_mass_is_hoped_for_and_weighed() -> None:
    """A wooden paddle board read 0.917 kg (declared 0.863) is too heavy for its handle in
    the rules; the lightest plausible reading lifts it, and the lift weighs it."""
    out = run_closed_loop("procedural-v1/train/0132", "utamp2-perceived", grounding="symbolic")
    assert out.success, out.failure
    assert (out.n_looks, out.n_weighings) == (1, 1)
