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
from utamp_gym.sim.control import ArmDriver, LinePath, Timings, ignoring
from utamp_gym.sim.decode import (
    MacroAction,
    footprint_centre,
    slide_vector,
)
from utamp_gym.sim.edge import place_edge, slide_edge
from utamp_gym.sim.grasp_phases import (
    APPROACH,
    TEST_LIFT,
    MissedGrasp,
    check_lift,
    grasp,
    let_go_and_look_again,
    lift_test_trouble,
    release_and_retreat,
    verify_lift,
)
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
    sweep_reach,
    turn_sink,
    turned_in_hand,
    verify_on,
)
from utamp_gym.sim.payload import LoadReading, hand_force_now, hold_and_measure, payload_failure
from utamp_gym.sim.placement import plan_place

PLACE = (0.15, 0.6)  # pre-place -> place
SLIDE = (0.12, 0.3)  # pushing/pulling an object over its support
DROP_SLIP, DROP_TILT_DEG = 0.05, 30.0  # ... during transport: the object was dropped
REGRASP_SLIP, REGRASP_TILT_DEG = 0.003, 1.0  # ... during transport: re-aim the placement
SLIDE_TOL = 0.02  # m, slid footprint centre within this of the space centre
CARRY_HOLD_S = 0.04  # s the arm holds over the support while its load is measured
#: a guarded descent: an upward push on the held object this strong (N, measured from the
#: joint torques) at the place pose, and stronger than the object's weight, means it landed
#: early; unless the wrist camera sees it resting at its place pose all the same (`_rests_at`:
#: it slid up in the pads as the hand pressed on), the arm backs up, looks again and aims
#: anew, at most `PLACE_ATTEMPTS` times. (A support may carry up to the whole weight
#: unpressed: a pan held by its handle sags onto it.)
CONTACT_N = 5.0
PLACE_ATTEMPTS = 3
#: the descent is guarded as it moves (`contact_guard`): it stops where the hand carries
#: nothing any more (the load on it, from the joint torques and the arm's dynamic model,
#: below `GUARD_FREE` of the object's weight for `GUARD_CHECKS` checks in a row,
#: `control.GUARD_EVERY` physics steps apart) more than `GUARD_MARGIN` m above the place pose:
#: the object rests on something and the fingers slide down along it. One that slipped down
#: in the pads on the way is then not pressed on down (a board pushed 1.6 cm further slips
#: out of the pads and stays as the hand backs up): it is let go where it stopped if it rests
#: within `LANDED_SHIFT` m / `LANDED_TURN_DEG` of its place pose (`_rests_at`), else the arm
#: backs up, looks again and aims anew as after an early landing. A support pressed on (a
#: rim) or carrying part of the weight (a pan sagging onto it) does not stop the descent.
GUARD_CHECKS = 3
GUARD_MARGIN = 0.006
GUARD_FREE, GUARD_MIN_WEIGHT_N = 0.15, 2.0
LANDED_SHIFT, LANDED_TURN_DEG = 0.008, 3.0
GRASP_ATTEMPTS = 2
#: m: a held object reaching farther than this out of the hand (beyond the hand's own
#: 10 cm half length) is lifted with room to turn in the hand (`measure.turn_sink`), carried
#: with its turned pose in the collision model (`measure.turned_in_hand`) and over its
#: support at its lift height (`place`)
SWEEP_REACH = 0.15


# ------------------------------------------------------------------ skills
def pick(st: SimState, act: MacroAction) -> None:
    """Grasp the member and lift the object off its support; raises on failure.

    A wrong pose estimate shows physically, and the grasp is then undone and tried again
    after a new look (`GRASP_ATTEMPTS` in all; the last one lifts without the test and its
    failure is the action's): the approach stopped short (`grasp`), the fingers closed on
    nothing, or the object slipped or turned in the hand in the first `TEST_LIFT` of the
    lift (grasped off its centre), after which the arm sets it back down. A retry starts
    only if the object still stands where it stood (`let_go_and_look_again`)."""
    sym = act.grasp
    if st.held is not None:
        raise SkillFailure(f"cannot pick {sym.obj}: the hand already holds {st.held.obj}")
    before = snapshot(st, {sym.obj})
    support, looked = st.stack().get(sym.obj), st.estimate(sym.obj)
    t = st.world.scene.type_of(sym.obj)
    sweeps = sweep_reach(t, sym.member) > SWEEP_REACH
    # the lift is judged at the usual height (`lift_height` without the room to turn): the
    # room is climbed after, so a slow creep in the hand is not judged over a longer lift
    judged = lift_height(st, sym.obj)
    lift = lift_height(st, sym.obj, turn_sink(t, sym.member)) if sweeps else judged
    for attempt in range(1, GRASP_ATTEMPTS + 1):
        last = attempt == GRASP_ATTEMPTS
        try:
            _, path, held = grasp(st, sym, lift)
        except MissedGrasp as exc:
            if last:
                raise
            let_go_and_look_again(st, sym.obj, (support, looked), before, str(exc))
            continue
        start_obj, start_tcp = obj_pose(st, sym.obj), st.arm.tcp()
        check_lift(st, held, path)
        up, room = path.split(judged) if lift > judged else (path, None)
        if last:
            st.arm.move_line(up, *APPROACH)
            break
        test, rest = up.split(TEST_LIFT)
        st.arm.move_line(test, *APPROACH)
        trouble = lift_test_trouble(st, held)
        if trouble is None:
            st.arm.move_line(rest, *APPROACH)
            break
        st.arm.move_line(test.reversed(), *PLACE)  # set it back down where it stood
        let_go_and_look_again(st, sym.obj, (support, looked), before, trouble)
    verify_lift(st, held, start_obj, start_tcp, before)
    if room is not None and room.length > 0.0:
        st.arm.move_line(room, *APPROACH)


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
    # an object reaching far out of the hand comes over its support at the height it was
    # lifted to, above the others (it would sweep a neighbour on a lower path), and may
    # turn in the hand on the way (its pads creep under its weight's moment)
    t = st.world.scene.type_of(name)
    sweeps = sweep_reach(t, held.member) > SWEEP_REACH
    carry = float(arm.tcp()[2, 3]) if sweeps else None
    what = f"carrying {name} to {act.support}"

    def carry_to(q: np.ndarray) -> None:
        turned = turned_in_hand(t, arm.tcp(), held.belief) if sweeps else None
        arm.transfer(q, held=(held.body, held.belief), turned=turned, what=what)

    up = plan_place(st, held, act, carry)
    carry_to(up.end)
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
        up = plan_place(st, held, act, carry)
        carry_to(up.end)

    def aim_again() -> LinePath:
        path = plan_place(st, held, act, carry)
        carry_to(path.end)
        return path

    up = relook.aim_place(st, act.support, up, aim_again)  # the wrist camera on the support
    weight = -float(carried.force[2])
    for attempt in range(1, PLACE_ATTEMPTS + 1):  # a guarded descent
        target = arm.tcp() @ held.belief  # where the object is to come to rest
        target[2, 3] -= up.length
        stopped = arm.move_line(up.reversed(), *PLACE, until=contact_guard(arm, carried, up))
        if stopped and _rests_at(st, name, target):  # it came to rest where it was to: let go
            break
        push = hold_and_measure(arm, CARRY_HOLD_S).force[2] - carried.force[2]
        if not (stopped or landed_early(push, weight)) or attempt == PLACE_ATTEMPTS:
            break
        if not stopped and _rests_at(st, name, target):  # pressed on down at its place pose
            break
        # it landed early (on a rim, say): back up, look again, aim anew
        arm.move_line(up, *PLACE)
        if st.estimator is not None:
            st.estimator.forget(act.support)
        _looked_again(st, held, always=True)
        up = plan_place(st, held, act, carry)
        carry_to(up.end)
    release_and_retreat(st, name, held.opening)
    settle_objects(st)
    verify_on(st, name, act.support)
    moved = disturbed(st, before)
    if moved:
        raise SkillFailure(f"placing {name} on {act.support} toppled the stack: {moved}")


def contact_guard(arm: ArmDriver, carried: LoadReading, up: LinePath) -> Callable[[], bool]:
    """The condition that stops a place descent along `up` reversed (from its top, where the
    arm is): the hand carries nothing any more (the load on it from the joint torques in
    motion below `GUARD_FREE` of the `carried` weight) for `GUARD_CHECKS` checks in a row,
    more than `GUARD_MARGIN` above the place pose; never for an object lighter than
    `GUARD_MIN_WEIGHT_N` (its weight is within the estimate's noise in motion)."""
    weight = -float(carried.force[2])
    if weight < GUARD_MIN_WEIGHT_N:
        return lambda: False
    bottom = float(arm.tcp()[2, 3]) - up.length
    count = 0

    def touched() -> bool:
        nonlocal count
        if float(arm.tcp()[2, 3]) - bottom <= GUARD_MARGIN:
            return False
        free = float(np.linalg.norm(hand_force_now(arm))) < GUARD_FREE * weight
        count = count + 1 if free else 0
        return count >= GUARD_CHECKS

    return touched


def _rests_at(st: SimState, name: str, target: np.ndarray) -> bool:
    """True if the wrist camera sees the held `name` within `LANDED_SHIFT` / `LANDED_TURN_DEG`
    of `target` (beyond what estimation noise explains, as in `_looked_again`): a descent
    stopped on contact has set it down where it was to go (it sagged or slipped down in the
    pads on the way), not on something in between."""
    shift, angle = pose_change(target, relook.in_hand(st, name))
    return not _moved_beyond(st, shift, angle, LANDED_SHIFT, LANDED_TURN_DEG)


def _moved_beyond(st: SimState, shift: float, angle: float, tol: float, tol_deg: float) -> bool:
    """True if a pose difference of `shift` m / `angle` degrees between two wrist-camera
    estimates exceeds `tol` / `tol_deg` beyond what the estimation noise explains (3 standard
    deviations of a difference of two estimates)."""
    noise = 0.0 if st.estimator is None else st.estimator.noise
    explained = 3 * math.sqrt(2)
    return shift > tol + explained * noise or angle > tol_deg + explained * yaw_noise_deg(noise)


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
    if always or _moved_beyond(st, shift, angle, REGRASP_SLIP, REGRASP_TILT_DEG):
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
    g, _, held = grasp(st, sym)
    believed = arm.tcp() @ held.belief
    offset = slide_vector(t, believed, np.asarray(spaces[act.space].position))
    near = arm.sync(arm.near, gap=arm.gap())
    with ignoring(near, st.world.geom_ids[sym.obj]):
        path = arm.line(
            arm.q(), g.tcp, offset, near.is_valid, what=f"sliding {sym.obj} into {act.space}"
        )
    arm.move_line(path, *SLIDE)
    release_and_retreat(st, sym.obj, g.opening)
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
    {
        "pick-support": pick,
        "place-support": place,
        "slide-support": slide,
        "slide-edge": slide_edge,  # the extended domain's (`utamp_gym.sim.edge`)
        "place-edge": place_edge,
    }
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
            release_and_retreat(st, st.held.obj, st.held.opening)
            settle_objects(st, min_s=0.1, max_s=0.6)
    timings = st.arm.timings.as_dict(time.perf_counter() - t0)
    return MacroResult(ok, reason, timings, retries=tuple(st.retries))


def _firmly_held(st: SimState) -> bool:
    assert st.held is not None
    slip, tilt = grasp_drift(st, st.held)
    return st.arm.holds_something() and slip <= DROP_SLIP and tilt <= DROP_TILT_DEG
