"""The three U-TAMP-2 macro skills executed in physics: pick, place and slide.

Each skill decodes its symbols against the *current* simulated poses (`decode`),
grounds them with IK and OMPL (`control.ArmDriver`) and runs the motion through the
position servos. Success is then measured, never assumed: the gap of the closed
fingers, how far the object rose with the hand, whether it stayed in the grasp, the
load on the hand from the joint torques (`payload`: over the Panda's 3 kg, or a joint at
its torque limit, fails), what it rests on after release (`stack_from_poses`,
`rests_on_top`), whether anything else moved. The symbolic layer is not consulted.
Failures come back as a `MacroResult` with a reason naming the object.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

from utamp_gym.backend import MacroResult, yaw_noise_deg
from utamp_gym.errors import GroundingError
from utamp_gym.sim import relook
from utamp_gym.sim.control import LinePath, Timings, ignoring
from utamp_gym.sim.decode import (
    GraspPose,
    GraspSymbols,
    MacroAction,
    footprint_centre,
    slide_vector,
)
from utamp_gym.sim.grasping import plan_grasp, weight_moment
from utamp_gym.sim.measure import (
    Held,
    SimState,
    SkillFailure,
    disturbed,
    grasp_drift,
    lift_height,
    obj_pose,
    pose_change,
    riders,
    settle_objects,
    snapshot,
    verify_on,
)
from utamp_gym.sim.payload import hold_and_measure, payload_failure
from utamp_gym.sim.placement import plan_place
from utamp_gym.sim.world import object_orientation

APPROACH = (0.25, 1.0)  # m/s, m/s^2: pre-grasp -> grasp, lift, retreat
PLACE = (0.15, 0.6)  # pre-place -> place
SLIDE = (0.12, 0.3)  # pushing/pulling an object over its support
RELEASE_CLEARANCE = 0.006  # m the fingers open beyond the held width before moving away
RETREAT = 0.10  # m up after releasing
MAX_SLIP = 0.02  # m, held object offset change while lifting that counts as slipping
MAX_TILT_DEG = 15.0  # held object rotation while lifting that counts as pivoting
DROP_SLIP, DROP_TILT_DEG = 0.05, 30.0  # ... during transport: the object was dropped
REGRASP_SLIP, REGRASP_TILT_DEG = 0.003, 1.0  # ... during transport: re-aim the placement
SLIDE_TOL = 0.02  # m, slid footprint centre within this of the space centre
CARRY_HOLD_S = 0.04  # s the arm holds over the support while its load is measured
#: a guarded descent: an upward push on the held object this strong (N, measured from the
#: joint torques) at the place pose, and stronger than the object's weight, means it landed
#: early; the arm backs up, looks again and aims anew, at most `PLACE_ATTEMPTS` times. (A
#: support may carry up to the whole weight unpressed: a pan held by its handle sags onto it.)
CONTACT_N = 5.0
PLACE_ATTEMPTS = 3
#: the first centimetre of a lift is a test: drift in the hand beyond these by then (or
#: fingers that closed on nothing) undoes the grasp, which is tried again (`pick`)
TEST_LIFT = 0.01  # m
TEST_SLIP, TEST_TILT_DEG = 0.004, 3.0
GRASP_ATTEMPTS = 2
#: an approach that ends this far from the grasp pose landed on something (`_grasp`): a
#: finger on a mug's rim stops the hand 36-49 mm short; a good grasp ends within 3 mm,
#: the palm resting on an upside-down pot's floor included
APPROACH_STOP = 0.01  # m
MAX_TURN_DEG = 15.0  # an object turned further by a failed attempt is not grasped again


class MissedGrasp(SkillFailure):
    """The hand stopped short of the grasp pose or the fingers closed on nothing: the object
    was not lifted, the grasp may be retried."""


# ------------------------------------------------------------------ shared phases
def _grasp(st: SimState, sym: GraspSymbols, lift: float = 0.0) -> tuple[GraspPose, LinePath, Held]:
    """Move to the pre-grasp, approach, close the fingers; check they hold something.

    The approach is guarded: a hand held up more than `APPROACH_STOP` short of the grasp
    pose (the joint positions against their targets) means a finger landed on something;
    the hand backs off and `MissedGrasp` is raised, as when the fingers close on nothing.
    Returns the grasp, the planned lift path and what is held. Sets `st.held` as soon as
    the fingers close, so a later failure lets go.
    """
    arm = st.arm
    g, approach, up = _to_pregrasp(st, sym, lift)
    # the wrist camera looks closely before the descent (re-aims) and before closing (aborts)
    g, approach, up = relook.aim_grasp(
        st, sym, g, (g, approach, up), lambda: _to_pregrasp(st, sym, lift)
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


def _to_pregrasp(
    st: SimState, sym: GraspSymbols, lift: float
) -> tuple[GraspPose, LinePath, LinePath]:
    """Plan the grasp (`grasping.plan_grasp`) and move the hand to its pre-grasp pose."""
    g, approach, up = plan_grasp(st, sym, lift)
    st.arm.set_gripper(g.opening)
    st.arm.transfer(approach.q[0], what=f"moving to grasp {sym.obj}")
    return g, approach, up


def _release_and_retreat(st: SimState, obj: str, opening: float) -> None:
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


# ------------------------------------------------------------------ skills
def pick(st: SimState, act: MacroAction) -> None:
    """Grasp the member and lift the object off its support; raises on failure.

    A wrong pose estimate shows physically, and the grasp is then undone and tried again
    after a new look (`GRASP_ATTEMPTS` in all; the last one lifts without the test and its
    failure is the action's): the approach stopped short (`_grasp`), the fingers closed on
    nothing, or the object slipped or turned in the hand in the first `TEST_LIFT` of the
    lift (grasped off its centre), after which the arm sets it back down. A retry starts
    only if the object still stands where it stood (`_let_go_and_look_again`)."""
    sym = act.grasp
    if st.held is not None:
        raise SkillFailure(f"cannot pick {sym.obj}: the hand already holds {st.held.obj}")
    before = snapshot(st, {sym.obj})
    support, looked = st.stack().get(sym.obj), st.estimate(sym.obj)
    lift = lift_height(st, sym.obj)
    for attempt in range(1, GRASP_ATTEMPTS + 1):
        last = attempt == GRASP_ATTEMPTS
        try:
            _, path, held = _grasp(st, sym, lift)
        except MissedGrasp as exc:
            if last:
                raise
            _let_go_and_look_again(st, sym.obj, (support, looked), before, str(exc))
            continue
        start_obj, start_tcp = obj_pose(st, sym.obj), st.arm.tcp()
        _check_lift(st, held, path)
        if last:
            st.arm.move_line(path, *APPROACH)
            break
        test, rest = path.split(TEST_LIFT)
        st.arm.move_line(test, *APPROACH)
        trouble = _test_lift_trouble(st, held)
        if trouble is None:
            st.arm.move_line(rest, *APPROACH)
            break
        st.arm.move_line(test.reversed(), *PLACE)  # set it back down where it stood
        _let_go_and_look_again(st, sym.obj, (support, looked), before, trouble)
    _verify_lift(st, held, start_obj, start_tcp, before)


def _check_lift(st: SimState, held: Held, path: LinePath) -> None:
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


def _test_lift_trouble(st: SimState, held: Held) -> str | None:
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


def _let_go_and_look_again(
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
        _release_and_retreat(st, obj, st.held.opening)
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


def _verify_lift(
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


def place(st: SimState, act: MacroAction) -> None:
    """Carry the held object over the support's centroid, lower it, release, verify."""
    name, held, arm = act.grasp.obj, st.held, st.arm
    if held is None or held.obj != name:
        what = "nothing" if held is None else held.obj
        raise SkillFailure(f"cannot place {name}: the hand holds {what}")
    slip, tilt = grasp_drift(st, held)
    if not arm.holds_something() or slip > DROP_SLIP or tilt > DROP_TILT_DEG:
        raise SkillFailure(f"{name} is no longer in the hand (it moved {slip * 100:.1f} cm)")
    before = snapshot(st, {name})
    up = plan_place(st, held, act)
    what = f"carrying {name} to {act.support}"
    arm.transfer(up.end, held=(held.body, held.belief), what=what)
    slip, tilt = grasp_drift(st, held)
    if not arm.holds_something() or slip > DROP_SLIP or tilt > DROP_TILT_DEG:
        raise SkillFailure(
            f"{name} dropped during transport (moved {slip * 100:.1f} cm, {tilt:.0f} deg "
            "in the hand)"
        )
    carried = hold_and_measure(arm, CARRY_HOLD_S)
    overload = payload_failure(name, carried, while_="carrying")
    if overload:
        raise SkillFailure(overload)
    if _looked_again(st, held):  # it turned in the hand (or the last look was off): re-aim
        up = plan_place(st, held, act)
        arm.transfer(up.end, held=(held.body, held.belief), what=what)

    def aim_again() -> LinePath:
        path = plan_place(st, held, act)
        arm.transfer(path.end, held=(held.body, held.belief), what=what)
        return path

    up = relook.aim_place(st, act.support, up, aim_again)  # the wrist camera on the support
    for attempt in range(1, PLACE_ATTEMPTS + 1):  # a guarded descent
        arm.move_line(up.reversed(), *PLACE)
        push = hold_and_measure(arm, CARRY_HOLD_S).force[2] - carried.force[2]
        if not landed_early(push, -carried.force[2]) or attempt == PLACE_ATTEMPTS:
            break
        # it landed early (on a rim, say): back up, look again, aim anew
        arm.move_line(up, *PLACE)
        if st.estimator is not None:
            st.estimator.forget(act.support)
        _looked_again(st, held, always=True)
        up = plan_place(st, held, act)
        arm.transfer(up.end, held=(held.body, held.belief), what=what)
    _release_and_retreat(st, name, held.opening)
    settle_objects(st)
    verify_on(st, name, act.support)
    moved = disturbed(st, before)
    if moved:
        raise SkillFailure(f"placing {name} on {act.support} toppled the stack: {moved}")


def landed_early(push: float, weight: float) -> bool:
    """True if an upward push of `push` N on a held object weighing `weight` N (both measured
    from the joint torques) at its place pose means it landed early (`CONTACT_N`)."""
    return push > max(CONTACT_N, weight)


def _looked_again(st: SimState, held: Held, *, always: bool = False) -> bool:
    """Look at the held object again before lowering it (a wrist camera) and adopt the new
    estimate if it differs from the belief by more than `REGRASP_SLIP` / `REGRASP_TILT_DEG`
    beyond what estimation noise explains (3 standard deviations of a difference), or
    `always`."""
    new = np.linalg.inv(st.arm.tcp()) @ relook.in_hand(st, held.obj)
    shift, angle = pose_change(held.belief, new)
    noise = 0.0 if st.estimator is None else st.estimator.noise
    explained = 3 * math.sqrt(2)
    if (
        always
        or shift > REGRASP_SLIP + explained * noise
        or angle > REGRASP_TILT_DEG + explained * yaw_noise_deg(noise)
    ):
        held.belief = new
        return True
    return False


def slide(st: SimState, act: MacroAction) -> None:
    """Grasp, drag the object over its support into the free space, release, verify."""
    sym, arm = act.grasp, st.arm
    if st.held is not None:
        raise SkillFailure(f"cannot slide {sym.obj}: the hand already holds {st.held.obj}")
    spaces = {s.name: s for s in st.world.scene.spaces}
    if act.space not in spaces:
        raise GroundingError(f"unknown space '{act.space}'; valid: {', '.join(spaces)}")
    stack = st.stack()
    above = riders(stack, sym.obj)
    before = snapshot(st, {sym.obj, *above})
    t = st.world.scene.type_of(sym.obj)
    g, _, held = _grasp(st, sym)
    believed = arm.tcp() @ held.belief
    offset = slide_vector(t, believed, np.asarray(spaces[act.space].position))
    near = arm.sync(arm.near, gap=arm.gap())
    with ignoring(near, st.world.geom_ids[sym.obj]):
        path = arm.line(
            arm.q(), g.tcp, offset, near.is_valid, what=f"sliding {sym.obj} into {act.space}"
        )
    arm.move_line(path, *SLIDE)
    _release_and_retreat(st, sym.obj, g.opening)
    settle_objects(st)
    centre = footprint_centre(t, obj_pose(st, sym.obj))
    miss = float(np.linalg.norm(centre - np.asarray(spaces[act.space].position)))
    if miss > SLIDE_TOL:
        raise SkillFailure(
            f"slide did not reach {act.space}: {sym.obj}'s footprint centre is "
            f"{miss * 100:.1f} cm from the space centre"
        )
    for rider in above:
        verify_on(st, rider, stack[rider] or sym.obj)
    moved = disturbed(st, before)
    if moved:
        raise SkillFailure(f"sliding {sym.obj} disturbed the scene: {moved}")


SKILLS: Mapping[str, Callable[[SimState, MacroAction], None]] = MappingProxyType(
    {"pick-support": pick, "place-support": place, "slide-support": slide}
)


def run_skill(st: SimState, act: MacroAction) -> MacroResult:
    """Execute one macro action and report; after a failure the hand keeps only an object
    it held before and still holds firmly (a failed place), else it lets go."""
    t0 = time.perf_counter()
    st.arm.timings = Timings()
    if st.estimator is not None:
        st.estimator.new_look()
    held_before = st.held
    st.retries.clear()
    try:
        SKILLS[act.kind](st, act)
        ok, reason = True, None
    except (SkillFailure, GroundingError) as exc:
        ok, reason = False, str(exc)
        if st.estimator is not None:  # after a failure the robot looks at them again
            st.estimator.forget(act.grasp.obj, act.support)
        if st.held is not None and (st.held is not held_before or not _firmly_held(st)):
            _release_and_retreat(st, st.held.obj, st.held.opening)
            settle_objects(st, min_s=0.1, max_s=0.6)
    timings = st.arm.timings.as_dict(time.perf_counter() - t0)
    return MacroResult(ok, reason, timings, retries=tuple(st.retries))


def _firmly_held(st: SimState) -> bool:
    assert st.held is not None
    slip, tilt = grasp_drift(st, st.held)
    return st.arm.holds_something() and slip <= DROP_SLIP and tilt <= DROP_TILT_DEG
