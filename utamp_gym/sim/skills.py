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

import itertools
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from types import MappingProxyType

import numpy as np

from utamp_gym.backend import MacroResult, yaw_noise_deg
from utamp_gym.errors import GroundingError
from utamp_gym.robot.collision import CollisionChecker
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.sim import relook
from utamp_gym.sim.bodies import BODY_PREFIX
from utamp_gym.sim.control import ArmDriver, LinePath, Timings, allowing, ignoring
from utamp_gym.sim.decode import (
    FINGER_CLEARANCE,
    MAX_OPENING,
    PLACE_DROP,
    TIP_BELOW_TCP,
    GraspPose,
    GraspSymbols,
    MacroAction,
    footprint_centre,
    grasp_candidates,
    hand_for_object,
    place_object_pose,
    slide_vector,
    support_point,
    world_aabb,
    yaw_of,
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
    verify_on,
)
from utamp_gym.sim.payload import hold_and_measure, payload_failure
from utamp_gym.sim.world import object_orientation

APPROACH = (0.25, 1.0)  # m/s, m/s^2: pre-grasp -> grasp, lift, retreat
PLACE = (0.15, 0.6)  # pre-place -> place
SLIDE = (0.12, 0.3)  # pushing/pulling an object over its support
RELEASE_CLEARANCE = 0.006  # m the fingers open beyond the held width before moving away
PREPLACE = 0.10  # m above the place pose
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
UNCERTAINTY_SIGMAS = 3.0  # the fingers open this many pose-noise deviations wider a side
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
#: a placement on a table slot tries its position, then spots this far apart within this
#: radius of it (`_slot_spots`)
SPOT_STEP, SPOT_RADIUS = 0.03, 0.09  # m
#: m: spots that leave this much room to every other object come first (a tumbler set down
#: 1 mm from another could not be lifted past it later)
SPOT_GAP = 0.04
#: m a grasp from above is raised by, in turn, when no arm configuration reaches it, while
#: the pads keep `PAD_HOLD` of the member between them (`_raised`): a plate in a larger
#: plate's well (procedural-v1/test-count/0063) is pinched 15 mm higher, 7 mm of its rim
GRASP_RAISES, PAD_HOLD = (0.005, 0.01, 0.015), 0.006
#: m above an object support a held object is released at, in turn: a plate held by its rim
#: over a plate whose rim rises around it would put a finger 4 mm into the lower rim at the
#: usual `PLACE_DROP`; it is let go 1-2 cm higher and falls into the lower plate's well
PLACE_DROPS = (PLACE_DROP, PLACE_DROP + 0.01, PLACE_DROP + 0.02)


class MissedGrasp(SkillFailure):
    """The hand stopped short of the grasp pose or the fingers closed on nothing: the object
    was not lifted, the grasp may be retried."""


# ------------------------------------------------------------------ shared phases
def _plan_grasp(
    st: SimState, sym: GraspSymbols, lift: float
) -> tuple[GraspPose, LinePath, LinePath]:
    """(grasp, approach path pre-grasp -> grasp, lift path) or `GroundingError`.

    Tries both finger-axis signs and several IK solutions; a solution is kept only if
    the straight approach and the lift (`lift` m up, 0: none) are feasible from it.
    """
    arm, world = st.arm, st.world
    t = world.scene.type_of(sym.obj)
    member = _member_geoms(st, sym.obj, sym.member)
    rest = [g for g in world.geom_ids[sym.obj] if g not in member]
    fingers = set(arm.ids.finger_geom_ids.tolist()) | set(arm.ids.finger_pad_geom_ids.tolist())
    palm = [g for g in arm.ids.geom_ids.tolist() if g not in fingers]
    tried = []
    candidates = grasp_candidates(t, sym, st.estimate(sym.obj), prefer_x=arm.tcp()[:3, 0])
    candidates += _raised(t, sym, st.estimate(sym.obj), candidates)
    noise = 0.0 if st.estimator is None else st.estimator.noise
    if candidates[0].width > MAX_OPENING:
        raise SkillFailure(
            f"cannot grasp {sym.obj} by its {sym.member}: it is {candidates[0].width * 100:.0f} cm"
            f" between the fingers, the hand opens {MAX_OPENING * 100:.0f} cm"
        )
    for g in candidates:
        near = arm.sync(arm.near, gap=g.opening)
        # the fingers may touch the member only; the palm may rest against the rest of the
        # object (an upside-down pot's floor above its lug), as it would in the real hand
        with ignoring(near, member), allowing(near, palm, rest):
            for q in arm.ik_solutions(g.tcp, near.is_valid):
                # the widest opening that fits: room for the error of the pose estimate
                for opening in _openings(g, noise):
                    wide = replace(g, opening=opening)
                    arm.sync(near, gap=opening)
                    try:
                        if not near.is_valid(q):
                            continue
                        back, up = _approach_and_lift(arm, wide, q, lift, sym.obj, near)
                    except GroundingError as exc:
                        tried.append(str(exc))
                        continue
                    finally:
                        arm.sync(near, gap=g.opening)  # the IK search goes on at the narrowest
                    return wide, back.reversed(), up
        tried.append("no collision-free IK solution")
    raise GroundingError(
        f"IK infeasible: cannot grasp {sym.obj} by its {sym.member} with the palm on "
        f"'{sym.palm}' ({'; '.join(dict.fromkeys(tried))})"
    )


def _raised(
    t: ObjectType, sym: GraspSymbols, pose: np.ndarray, grasps: list[GraspPose]
) -> list[GraspPose]:
    """The grasps from above again, `GRASP_RAISES` higher, while the pads still hold
    `PAD_HOLD` of the member: a plate's rim in a larger plate's well, whose rim rises
    where the outer finger goes down, is pinched higher up."""
    top = float(world_aabb(t.members[sym.member].box, pose)[1][2])
    out = []
    for rise in GRASP_RAISES:
        for g in grasps:
            tip = float(g.tcp[2, 3]) + rise - TIP_BELOW_TCP
            if g.tcp[2, 2] > -0.5 or top - tip < PAD_HOLD:
                continue  # not from above, or too little of the member between the pads
            up = np.array([0.0, 0.0, rise])
            tcp, pre = g.tcp.copy(), g.pregrasp.copy()
            tcp[:3, 3] += up
            pre[:3, 3] += up
            out.append(replace(g, tcp=tcp, pregrasp=pre))
    return out


def _member_geoms(st: SimState, obj: str, member: str) -> list[int]:
    """The geoms realising `member` of `obj` (the fingers may touch them, not the rest of the
    object: a finger must not land on a tray's rim next to its handle); all of the object's
    geoms if the member has none of its own (an edge realised by the body's wall)."""
    prefix = f"{BODY_PREFIX}{obj}/{member}"
    names = st.world.info.geom_names[obj]
    own = [
        g
        for g, name in zip(st.world.geom_ids[obj], names, strict=True)
        if name == prefix or name.startswith(prefix + "/")
    ]
    return own or list(st.world.geom_ids[obj])


def _openings(g: GraspPose, noise: float) -> tuple[float, ...]:
    """Pre-grasp finger openings to try, widest first: room for 3 standard deviations of the
    pose estimate's error on each side (within the hand's opening), then the member's width
    plus `FINGER_CLEARANCE` a side (`GraspPose.opening`)."""
    wide = min(MAX_OPENING, g.width + 2 * (FINGER_CLEARANCE + UNCERTAINTY_SIGMAS * noise))
    return (wide, g.opening) if wide > g.opening + 1e-9 else (g.opening,)


def _approach_and_lift(
    arm: ArmDriver, g: GraspPose, q: np.ndarray, lift: float, obj: str, near: CollisionChecker
) -> tuple[LinePath, LinePath]:
    """(path grasp -> pre-grasp, lift path) from grasp configuration `q`, or GroundingError."""
    back = arm.line(q, g.tcp, g.pregrasp[:3, 3] - g.tcp[:3, 3], near.is_valid, what="the approach")
    up = arm.line(q, g.tcp, np.array([0.0, 0.0, lift]), near.is_valid, what=f"lifting {obj}")
    return back, up


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
    """Plan the grasp (`_plan_grasp`) and move the hand to its pre-grasp pose."""
    g, approach, up = _plan_grasp(st, sym, lift)
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


def _slot_spots(st: SimState, slot: str) -> list[np.ndarray]:
    """Where on the table slot `slot` an object may be put, best first: the slot's position,
    then points `SPOT_STEP` apart within `SPOT_RADIUS` of it (and inside the slot's region),
    nearest first. A stack beside the slot, or the arm's reach, may leave no room at the
    position itself (a plate's rim over a neighbour's wall); a person would put it a few
    centimetres along."""
    centre = np.asarray(st.world.slot_positions[slot], dtype=float)
    region = next(s.region for s in st.world.scene.slots if s.name == slot)
    n = int(SPOT_RADIUS / SPOT_STEP)
    spots = []
    for i in range(-n, n + 1):
        for j in range(-n, n + 1):
            p = centre + np.array([i * SPOT_STEP, j * SPOT_STEP, 0.0])
            inside = all(region.min[k] + SPOT_STEP / 2 <= p[k] <= region.max[k] - SPOT_STEP / 2
                         for k in (0, 1))  # fmt: skip
            if (i or j) and inside and math.hypot(i, j) * SPOT_STEP <= SPOT_RADIUS + 1e-9:
                spots.append(p)
    spots.sort(key=lambda p: (round(float(np.linalg.norm(p - centre)), 6), float(p[0])))
    return [centre, *spots]


def _footprints(st: SimState, exclude: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """(min, max) x-y corners of every object but `exclude`, as the robot believes them."""
    scene = st.world.scene
    out = []
    for name in st.world.body_ids:
        if name != exclude:
            lo, hi = world_aabb(scene.type_of(name).bbox, st.estimate(name))
            out.append((lo[:2], hi[:2]))
    return out


def _crowded(t: ObjectType, pose: np.ndarray, others: list[tuple[np.ndarray, np.ndarray]]) -> bool:
    """Whether an object of type `t` at `pose` would stand nearer than `SPOT_GAP` to another."""
    lo, hi = (c[:2] for c in world_aabb(t.bbox, pose))
    for olo, ohi in others:
        gap = np.maximum(np.maximum(olo - hi, lo - ohi), 0.0)
        if float(np.hypot(*gap)) < SPOT_GAP:
            return True
    return False


def _support_surfaces(st: SimState, act: MacroAction) -> list[np.ndarray]:
    """Where the held object's footprint may be centred on its support, best first: on an
    object, the centre of its usable surface; on a slot, `_slot_spots`."""
    scene = st.world.scene
    if act.support in st.world.slot_positions:
        return _slot_spots(st, act.support)
    if act.support not in st.world.body_ids:
        valid = [*st.world.body_ids, *st.world.slot_positions]
        raise GroundingError(f"unknown support '{act.support}'; valid: {', '.join(valid)}")
    try:
        pose = st.estimate(act.support)
        return [support_point(scene.type_of(act.support), act.support_part, pose)]
    except GroundingError as exc:
        raise SkillFailure(f"cannot place {act.grasp.obj} on {act.support}: {exc}") from None


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
    up = _plan_place(st, held, act)
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
        up = _plan_place(st, held, act)
        arm.transfer(up.end, held=(held.body, held.belief), what=what)

    def aim_again() -> LinePath:
        path = _plan_place(st, held, act)
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
        up = _plan_place(st, held, act)
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


def _plan_place(st: SimState, held: Held, act: MacroAction) -> LinePath:
    """Path from the place configuration up to the pre-place one, or `GroundingError`.

    The object turns square to its support (its yaw); if that does not fit, it keeps its
    current yaw.
    """
    name, arm = held.obj, st.arm
    t, now = st.world.scene.type_of(name), arm.tcp() @ held.belief
    surfaces = _support_surfaces(st, act)
    base_yaw = yaw_of(st.estimate(act.support)[:3, :3]) if act.support in st.world.body_ids else 0.0
    tried = []
    near = arm.sync(arm.near, gap=arm.gap())
    near.attach(held.body, held.belief)
    world = st.world
    support = world.geom_ids.get(act.support, [world.table_geom_id])
    # lowering into a snug support (a board into a rimmed tray) may graze it: touching is
    # allowed there, and penetrating (in the robot's belief) as far as the estimates' error
    # allows (`relook.PLACE_ROOM_SIGMAS`); the guarded descent and the close look at the
    # support (`relook.aim_place`) take care of the rest
    try:
        with allowing(near, world.geom_ids[name], support, relook.place_room(st)):
            # square to the support first, else as held; on a slot, nearest its position; on
            # an object, released higher if the fingers would meet it (`PLACE_DROPS`)
            drops = (PLACE_DROP,) if act.support not in world.body_ids else PLACE_DROPS
            targets = [
                place_object_pose(t, now, surface, yaw=yaw, drop=drop)
                for drop, surface, yaw in itertools.product(drops, surfaces, (base_yaw, None))
            ]
            if act.support in world.slot_positions:  # spots that leave a finger room first
                others = _footprints(st, exclude=name)
                targets.sort(key=lambda target: _crowded(t, target, others))
            for target in targets:
                tcp = hand_for_object(target, held.belief)
                for q in arm.ik_solutions(tcp, near.is_valid):
                    try:
                        return arm.line(
                            q,
                            tcp,
                            np.array([0.0, 0.0, PREPLACE]),
                            near.is_valid,
                            what=f"lowering {name} onto {act.support}",
                        )
                    except GroundingError as exc:
                        tried.append(str(exc))
                tried.append("no collision-free IK solution")
    finally:
        near.detach()
    raise GroundingError(
        f"IK infeasible: cannot put {name} on {act.support} ({'; '.join(dict.fromkeys(tried))})"
    )


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
