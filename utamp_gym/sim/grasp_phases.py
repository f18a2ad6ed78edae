"""The phases the pick and slide skills share (`utamp_gym.sim.skills`): the guarded grasp,
the release, and the checks of a lift — the test lift, letting go and looking again, and
the measurements that decide whether the object came up in the hand.
"""

from __future__ import annotations

import numpy as np

from utamp_gym.errors import GroundingError
from utamp_gym.sim import relook
from utamp_gym.sim.control import LinePath, ignoring
from utamp_gym.sim.decode import GraspPose, GraspSymbols
from utamp_gym.sim.grasping import plan_grasp, weight_moment
from utamp_gym.sim.measure import (
    Held,
    SimState,
    SkillFailure,
    disturbed,
    grasp_drift,
    obj_pose,
    pose_change,
    settle_objects,
)
from utamp_gym.sim.payload import hold_and_measure, payload_failure
from utamp_gym.sim.world import object_orientation

APPROACH = (0.25, 1.0)  # m/s, m/s^2: pre-grasp -> grasp, lift, retreat
RELEASE_CLEARANCE = 0.006  # m the fingers open beyond the held width before moving away
RETREAT = 0.10  # m up after releasing
MAX_SLIP = 0.02  # m, held object offset change while lifting that counts as slipping
MAX_TILT_DEG = 15.0  # held object rotation while lifting that counts as pivoting
#: the first centimetre of a lift is a test: drift in the hand beyond these by then (or
#: fingers that closed on nothing) undoes the grasp, which is tried again (`pick`)
TEST_LIFT = 0.01  # m
TEST_SLIP, TEST_TILT_DEG = 0.004, 3.0
#: an approach that ends this far from the grasp pose landed on something (`grasp`): a
#: finger on a mug's rim stops the hand 36-49 mm short; a good grasp ends within 3 mm,
#: the palm resting on an upside-down pot's floor included
APPROACH_STOP = 0.01  # m
MAX_TURN_DEG = 15.0  # an object turned further by a failed attempt is not grasped again


class MissedGrasp(SkillFailure):
    """The hand stopped short of the grasp pose or the fingers closed on nothing: the object
    was not lifted, the grasp may be retried."""


def grasp(st: SimState, sym: GraspSymbols, lift: float = 0.0) -> tuple[GraspPose, LinePath, Held]:
    """Move to the pre-grasp, approach, close the fingers; check they hold something.

    The approach is guarded: a hand held up more than `APPROACH_STOP` short of the grasp
    pose (the joint positions against their targets) means a finger landed on something;
    the hand backs off and `MissedGrasp` is raised, as when the fingers close on nothing.
    Returns the grasp, the planned lift path and what is held. Sets `st.held` as soon as
    the fingers close, so a later failure lets go.
    """
    arm = st.arm
    g, approach, up = to_pregrasp(st, sym, lift)
    # the wrist camera looks closely before the descent (re-aims) and before closing (aborts)
    g, approach, up = relook.aim_grasp(
        st, sym, g, (g, approach, up), lambda: to_pregrasp(st, sym, lift)
    )
    arm.open_gripper(g.opening)
    arm.move_line(approach, *APPROACH)
    short = float(np.linalg.norm(arm.tcp()[:3, 3] - g.tcp[:3, 3]))
    if short > APPROACH_STOP:  # a guarded approach: it landed on something; back off
        arm.move_line(approach.reversed(), *APPROACH)
        raise MissedGrasp(
            f"the hand stopped short of the {sym.member} of {sym.obj} "
            f"({short * 1000:.0f} mm: a finger landed on something)"
        )
    off = relook.grasp_offset(st, sym, g)
    if off is not None:
        arm.move_line(approach.reversed(), *APPROACH)
        raise MissedGrasp(
            f"the wrist camera saw the {sym.member} of {sym.obj} {relook.describe(off)} "
            "before the fingers closed"
        )
    arm.expect_width(
        g.width, weight_moment(st.world.scene.type_of(sym.obj), obj_pose(st, sym.obj), g.tcp)
    )
    gap = arm.close_gripper()
    hand_t_world = np.linalg.inv(arm.tcp())
    tcp_t_obj = hand_t_world @ obj_pose(st, sym.obj)
    belief = hand_t_world @ relook.in_hand(st, sym.obj)  # in the hand: the wrist camera
    body = st.world.body_ids[sym.obj]
    st.held = Held(sym.obj, sym.member, body, tcp_t_obj, g.opening, sym, belief)
    if not arm.holds_something():
        raise MissedGrasp(
            f"grasp failed: the fingers closed on nothing at the {sym.member} of {sym.obj} "
            f"(gap {gap * 1000:.1f} mm)"
        )
    return g, up, st.held


def to_pregrasp(
    st: SimState, sym: GraspSymbols, lift: float
) -> tuple[GraspPose, LinePath, LinePath]:
    """Plan the grasp (`grasping.plan_grasp`) and move the hand to its pre-grasp pose."""
    g, approach, up = plan_grasp(st, sym, lift)
    st.arm.set_gripper(g.opening)
    st.arm.transfer(approach.q[0], what=f"moving to grasp {sym.obj}")
    return g, approach, up


def release_and_retreat(st: SimState, obj: str, opening: float) -> None:
    """Open the fingers, then move the hand up (as far as `RETREAT`), ignoring `obj`.

    Fingers that closed on nothing move up first and open above: opening them where they
    are would sweep a finger into an object that the missed grasp left leaning on it."""
    arm = st.arm
    empty = not arm.holds_something()
    if not empty:
        arm.open_gripper(opening, clear=RELEASE_CLEARANCE)
    st.held = None
    start, q = arm.kin.fk(arm.q()), arm.q()
    near = arm.sync(arm.near, gap=arm.gap() if empty else opening)
    with ignoring(near, st.world.geom_ids[obj]):
        for rise in (RETREAT, RETREAT / 2, RETREAT / 4):
            try:
                path = arm.line(
                    q, start, np.array([0.0, 0.0, rise]), near.is_valid, what="the retreat"
                )
            except GroundingError:
                continue
            arm.move_line(path, *APPROACH)
            break
    if empty:
        arm.open_gripper(opening)


def check_lift(st: SimState, held: Held, path: LinePath) -> None:
    """`GroundingError` if lifting the held object along `path` would collide (as believed)."""
    near = st.arm.sync(st.arm.near, gap=st.arm.gap())
    near.attach(held.body, held.belief)
    try:
        with near.tolerating(path.q[0]):
            blocked = [q for q in path.q if not near.is_valid(q)]
            if blocked:
                why = near.describe(near.contacts(blocked[0]))
                raise GroundingError(f"lifting {held.obj} would collide ({why})")
    finally:
        near.detach()


def lift_test_trouble(st: SimState, held: Held) -> str | None:
    """Why the grasp is not to be trusted after the test lift (`TEST_LIFT`), else None."""
    slip, tilt = grasp_drift(st, held)
    if not st.arm.holds_something():
        how = "slipped out of the fingers"
    elif tilt > TEST_TILT_DEG:
        how = f"turned {tilt:.1f} deg in the grasp"
    elif slip > TEST_SLIP:
        how = f"slipped {slip * 1000:.0f} mm in the grasp"
    else:
        return None
    return f"{held.obj} {how} in the first {TEST_LIFT * 100:.0f} cm of its lift"


def let_go_and_look_again(
    st: SimState,
    obj: str,
    where: tuple[str | None, np.ndarray],
    before: dict[str, tuple[np.ndarray, str | None]],
    trouble: str,
) -> None:
    """Open the hand, move up and look at `obj` again before another grasp, which is only
    tried if `obj` still stands on the same support `where[0]`, turned by at most
    `MAX_TURN_DEG` from the estimated pose `where[1]` it was planned for (its sides are the
    action's symbols), and nothing else moved."""
    support, looked = where
    if st.held is not None:
        release_and_retreat(st, obj, st.held.opening)
    settle_objects(st, min_s=0.1, max_s=0.6)
    if st.estimator is not None:
        st.estimator.forget(obj)
    tipped = object_orientation(st.world.model, st.data, obj) is None
    turned = pose_change(looked, st.estimate(obj))[1]  # estimates are level: the yaw
    what = (
        f"{obj} tipped over"
        if tipped
        else f"{obj} left {support}"
        if st.stack().get(obj) != support
        else f"{obj} turned {turned:.0f} deg"
        if turned > MAX_TURN_DEG
        else disturbed(st, before)
    )
    if what:
        raise SkillFailure(f"{trouble}; letting go of it: {what}")
    st.retries.append(trouble)


def verify_lift(
    st: SimState,
    held: Held,
    start_obj: np.ndarray,
    start_tcp: np.ndarray,
    before: dict[str, tuple[np.ndarray, str | None]],
) -> None:
    """Measure the lift just made: the load, how far the object rose with the hand, how it
    sits in the grasp, the rest of the scene; raises `SkillFailure` naming what went wrong."""
    arm, obj, member = st.arm, held.obj, held.member
    load = hold_and_measure(arm)
    hand_rise = arm.tcp()[2, 3] - start_tcp[2, 3]
    obj_rise = obj_pose(st, obj)[2, 3] - start_obj[2, 3]
    slip, tilt = grasp_drift(st, held)
    if not arm.holds_something():
        raise SkillFailure(f"{obj} slipped out of the grasp while lifting")
    overload = payload_failure(obj, load, while_="lifting")
    if overload:
        raise SkillFailure(overload)
    if obj_rise < 0.5 * hand_rise or tilt > MAX_TILT_DEG or slip > MAX_SLIP:
        how = (
            "it stayed down"
            if obj_rise < 0.5 * hand_rise
            else f"it pivoted {tilt:.0f} deg in the grasp"
            if tilt > MAX_TILT_DEG
            else f"it slipped {slip * 100:.1f} cm in the grasp"
        )
        raise SkillFailure(
            f"{obj} is not liftable by its {member}: {how} "
            f"(rose {obj_rise * 100:.1f} cm while the hand rose {hand_rise * 100:.1f} cm, "
            f"bearing {load.describe()} of it)"
        )
    if object_orientation(st.world.model, st.data, obj) is None:
        raise SkillFailure(f"{obj} tilted over in the grasp (it was grasped off its centre)")
    moved = disturbed(st, before)
    if moved:
        raise SkillFailure(f"picking {obj} disturbed the scene: {moved}")
    hand_t_world = np.linalg.inv(arm.tcp())  # as carried: measured, and looked at again
    held.tcp_t_obj = hand_t_world @ obj_pose(st, obj)
    held.belief = hand_t_world @ relook.in_hand(st, obj)
