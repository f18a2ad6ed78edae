"""The extended domain's ``slide-edge`` in physics: a flat board slid to the table's near edge
and pinched there (issue #39).

A board too wide for the open hand and too flat to pinch from above is taken as a person
takes it: pressed from above and dragged until it overhangs the table's edge, then pinched
across its thickness where it overhangs and lifted. The Panda reaches only the table's near
edge (behind its base, ``docs/results/edge_reach.md``), between `EDGE_Y` from its axis.

1. Press and drag (`drag_to_edge`): the closed fingertips come down on the middle of the
   board's top, `PRESS` below it (the servos then press with several tens of newtons, and the
   pads' friction, `affordances.edge.PAD_FRICTION`, beats the table's), and drag it first
   sideways to the target line `EDGE_Y` from the base's axis, then back until its back side
   overhangs the near edge by `OVERHANG` (`edge_overhang` of a deeper pinch; each leg a press
   of its own, the fingers closing across the drag); where it lagged the hand (a few
   centimetres), a drag of the measured error corrects it (`DRAG_ROUNDS`). The sweep must be
   clear of every other object.
2. Pinch (`edge_pinch`): the hand approaches horizontally from outside the table (its z
   along +x, towards the robot), the fingers open `MAX_OPENING` and closing vertically on the
   board's thickness, the pads `PAD_IN` inside the board's back end (or deeper: the rule's
   `utamp_gym.affordances.edge.edge_depth`), clear of the table's edge; it closes and lifts,
   and the lift is measured as a pick's (`grasp_phases.verify_lift`).

The action's grasp symbols are the board's body, palm ``back`` (the side facing the near edge at
the scene's yaw) and fingers ``on``/``under``; after it the hand holds the board.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np

from utamp_gym.affordances.edge import (
    BASE_CLEARANCE,
    EDGE_Y,
    OVERHANG,
    PAD_IN,
    edge_depth,
    edge_overhang,
)
from utamp_gym.errors import GroundingError
from utamp_gym.sim import relook
from utamp_gym.sim.control import ignoring
from utamp_gym.sim.decode import (
    MAX_OPENING,
    PLACE_DROP,
    TIP_BELOW_TCP,
    MacroAction,
    footprint_centre,
    world_aabb,
)
from utamp_gym.sim.grasp_phases import APPROACH, check_lift, verify_lift
from utamp_gym.sim.measure import (
    Held,
    SimState,
    SkillFailure,
    disturbed,
    lift_height,
    obj_pose,
    settle_objects,
    snapshot,
    verify_on,
)

PRESS = 0.006  # m the fingertips are commanded below the board's top while dragging
OVERHANG_TOL = 0.008  # m: an overhang this far off after the drags fails the action
PAD_HALF = 0.00925  # m: half the pads' length along the approach
PAD_CLEAR = 0.003  # m the pads stay short of the table's edge
RELEASE_DROP = (0.01, 0.005, 0.0)  # m the open hand goes down before backing off, in turn
#: m it then backs off by, in turn: the pads (`PAD_IN` + `PAD_HALF` in) clear the board's end
#: (and by as much more as a deeper pinch went in)
RELEASE_BACKOFF = (0.05, 0.04, 0.035)
PINCH_BACKOFF = (0.06, 0.04, 0.03)  # m the horizontal approach starts back from the pinch
DRAG = (0.12, 0.3)  # m/s, m/s^2
DRAG_ROUNDS = 2
MOVED = 0.005  # m: a board moved this far by a failed drag is not dragged along another line
SWEEP_MARGIN = 0.01  # m another object's footprint must clear the dragged board by
PRESS_ABOVE = 0.10  # m above the press point the hand comes down from
HAND_DOWN = np.diag([1.0, -1.0, -1.0])
#: (lo, hi) of the dragged board's world box -> the (x, y) error still to drag
Aim = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _aabb(st: SimState, name: str) -> tuple[np.ndarray, np.ndarray]:
    return world_aabb(st.world.scene.type_of(name).bbox, st.estimate(name))


def near_edge(st: SimState) -> float:
    """x (m, world) of the table's near edge, the one behind the robot's base."""
    return float(st.world.scene.table.body.box.min[0])


def target_y(lo: np.ndarray, hi: np.ndarray) -> list[float]:
    """Where (y, world) the board's middle may be dragged to, in turn: on its own side of the
    base's axis, `EDGE_Y` out, its near side `BASE_CLEARANCE` from the axis."""
    half = (hi[1] - lo[1]) / 2
    mid = (hi[1] + lo[1]) / 2
    side = 1.0 if mid >= 0 else -1.0
    ys = [side * y for y in EDGE_Y if y - half >= BASE_CLEARANCE - 1e-9]
    return ys


def _legs(shift: np.ndarray, y_first: bool) -> list[np.ndarray]:
    """The drag's two straight legs (3-vectors): along y then x, or x then y."""
    dy, dx = np.array([0.0, shift[1], 0.0]), np.array([shift[0], 0.0, 0.0])
    return [dy, dx] if y_first else [dx, dy]


def _in_the_way(
    st: SimState, obj: str, lo: np.ndarray, hi: np.ndarray, legs: list[np.ndarray]
) -> str:
    """The first other object whose footprint the board meets when dragged along `legs`
    (within `SWEEP_MARGIN`), or ""."""
    a_lo, a_hi, boxes = lo[:2].copy(), hi[:2].copy(), []
    for leg in legs:
        b_lo, b_hi = a_lo + leg[:2], a_hi + leg[:2]
        boxes.append((np.minimum(a_lo, b_lo), np.maximum(a_hi, b_hi)))
        a_lo, a_hi = b_lo, b_hi
    for other in st.world.body_ids:
        if other == obj:
            continue
        o_lo, o_hi = _aabb(st, other)
        for b_lo, b_hi in boxes:
            if np.all(o_lo[:2] < b_hi + SWEEP_MARGIN) and np.all(b_lo - SWEEP_MARGIN < o_hi[:2]):
                return other
    return ""


def _press_pose(x: float, y: float, top: float) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = HAND_DOWN
    out[:3, 3] = [x, y, top + TIP_BELOW_TCP - PRESS]
    return out


def press_drag(
    st: SimState, obj: str, goal: np.ndarray, y_first: bool, aim: Aim | None = None
) -> None:
    """Drag `obj` until its middle (of its world box) lies at `goal` (x, y): two straight
    legs (`y_first`: sideways first), each a press and drag (`_drag`), then a correcting
    drag of the error `aim` measures on its world box (default: of its middle from `goal`;
    `DRAG_ROUNDS`). `GroundingError` if an object is in the way or the arm cannot follow."""
    lo, hi = _aabb(st, obj)
    legs = _legs(goal - (lo[:2] + hi[:2]) / 2, y_first)
    other = _in_the_way(st, obj, lo, hi, legs)
    if other:
        raise GroundingError(f"{other} is in the way")
    for leg in legs:
        if np.abs(leg).max() >= 1e-3:
            _drag(st, obj, leg, DRAG)
    if aim is None:
        aim = lambda lo, hi: goal - (lo[:2] + hi[:2]) / 2  # noqa: E731
    for _ in range(DRAG_ROUNDS - 1):
        if st.estimator is not None:
            st.estimator.forget(obj)
        err = np.array([*aim(*_aabb(st, obj)), 0.0])
        if np.abs(err).max() >= 1e-3:
            _drag(st, obj, err, (DRAG[0] / 2, DRAG[1]))


def _drag(st: SimState, obj: str, leg: np.ndarray, speed: tuple[float, float]) -> None:
    """Press `obj` at its middle with the closed fingertips, drag it by `leg` (x, y[, 0]),
    rise and open the hand. The fingers close across the drag: along it, the board's pull
    on the pads would slide the fingers open instead of dragging it."""
    arm, geoms = st.arm, st.world.geom_ids[obj]
    if st.estimator is not None:
        st.estimator.forget(obj)
    lo, hi = _aabb(st, obj)
    leg = np.array([leg[0], leg[1], 0.0])
    press = _press_pose((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2])
    if abs(leg[1]) > abs(leg[0]):  # the fingers close along x
        press[:3, :3] = HAND_DOWN @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    above = press.copy()
    above[2, 3] += PRESS_ABOVE
    arm.set_gripper(0.0)
    arm.close_gripper(max_s=0.4)
    near = arm.sync(arm.near, gap=arm.gap())
    with ignoring(near, geoms):
        q = next(arm.ik_solutions(above, near.is_valid), None)
        if q is None:
            raise GroundingError(f"IK infeasible: no configuration over {obj} to press it")
        down = arm.line(q, above, np.array([0.0, 0.0, -PRESS_ABOVE]), near.is_valid,
                        what=f"pressing {obj}")  # fmt: skip
        path = arm.line(down.end, press, leg, near.is_valid, what=f"dragging {obj}")
    arm.transfer(q, what=f"moving over {obj}")
    arm.move_line(down, *APPROACH)
    arm.move_line(path, *speed)
    press[:3, 3] += leg
    up = arm.line(arm.q(), press, np.array([0.0, 0.0, PRESS_ABOVE]), lambda _q: True,
                  what="the retreat")  # fmt: skip
    arm.move_line(up, *APPROACH)
    settle_objects(st, min_s=0.05)


def drag_to_edge(st: SimState, obj: str) -> None:
    """Drag `obj` (`press_drag`, sideways first) until its back end overhangs the near edge
    by `OVERHANG` (`edge_overhang` of its pinch's depth), on the first line `target_y` the
    arm and the scene allow; raises `GroundingError` / `SkillFailure`."""
    lo, hi = _aabb(st, obj)
    start = _true_lo(st, obj)
    edge = near_edge(st)
    over = edge_overhang(edge_depth(st.world.scene.type_of(obj)))
    tried = []
    for y in target_y(lo, hi):
        goal = np.array([edge - over + (hi[0] - lo[0]) / 2, y])

        def aim(lo: np.ndarray, hi: np.ndarray, y: float = y) -> np.ndarray:
            return np.array([edge - over - lo[0], y - (lo[1] + hi[1]) / 2])

        try:
            press_drag(st, obj, goal, y_first=True, aim=aim)
        except GroundingError as exc:
            if np.abs(_true_lo(st, obj) - start).max() > MOVED:
                raise  # the drag began: no other line is tried
            tried.append(f"y {y:+.2f}: {exc}")
            continue
        _check_overhang(st, obj, edge, over)
        return
    raise GroundingError(f"cannot slide {obj} to the table's edge ({'; '.join(tried)})")


def _true_lo(st: SimState, obj: str) -> np.ndarray:
    """The (x, y) corner of `obj`'s world box where it truly is."""
    return world_aabb(st.world.scene.type_of(obj).bbox, obj_pose(st, obj))[0][:2]


def _check_overhang(st: SimState, obj: str, edge: float, wanted: float = OVERHANG) -> None:
    if st.estimator is not None:
        st.estimator.forget(obj)
    lo, _ = world_aabb(st.world.scene.type_of(obj).bbox, obj_pose(st, obj))
    over = edge - float(lo[0])
    if abs(over - wanted) > OVERHANG_TOL:
        raise SkillFailure(
            f"{obj} overhangs the table's edge by {over * 100:.1f} cm after the slide "
            f"(wanted {wanted * 100:.1f} cm)"
        )


def pinch_pose(
    lo: np.ndarray, hi: np.ndarray, roll: float, edge: float, depth: float = PAD_IN
) -> np.ndarray:
    """TCP pose pinching the overhang of a board with world extent `lo`..`hi`: `depth`
    inside its back end (or less, the pads `PAD_CLEAR` short of the table's edge at x =
    `edge`), at its mid-height, approaching along +x, the fingers closing vertically (`roll`
    +1 or -1: which way up the hand is)."""
    z = np.array([1.0, 0.0, 0.0])
    x = np.array([0.0, roll, 0.0])
    out = np.eye(4)
    out[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    x = min(lo[0] + depth, edge - PAD_HALF - PAD_CLEAR)
    out[:3, 3] = [x, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2]
    return out


def edge_pinch(
    st: SimState, act: MacroAction, before: dict[str, tuple[np.ndarray, str | None]]
) -> None:
    """Pinch the overhanging board (see the module docstring), lift it and measure the lift
    (`before`: the other objects' poses the action must leave alone)."""
    sym, arm = act.grasp, st.arm
    obj = sym.obj
    geoms = st.world.geom_ids[obj]
    if st.estimator is not None:
        st.estimator.forget(obj)
    lo, hi = _aabb(st, obj)
    lift = lift_height(st, obj)
    depth = edge_depth(st.world.scene.type_of(obj))
    tried = []
    near = arm.sync(arm.near, gap=MAX_OPENING)
    plan = None
    with ignoring(near, geoms):
        for roll in (1.0, -1.0):
            pinch = pinch_pose(lo, hi, roll, near_edge(st), depth)
            for q in arm.ik_solutions(pinch, near.is_valid, restarts=10):
                for dist in PINCH_BACKOFF:
                    try:
                        back = arm.line(q, pinch, np.array([-dist, 0.0, 0.0]), near.is_valid,
                                        what="the pinch's approach")  # fmt: skip
                    except GroundingError as exc:
                        tried.append(str(exc))
                        continue
                    plan = pinch, back
                    break
                if plan:
                    break
            if plan:
                break
    if plan is None:
        why = "; ".join(dict.fromkeys(tried)) or "no collision-free IK solution"
        raise GroundingError(f"IK infeasible: cannot pinch {obj} over the table's edge ({why})")
    pinch, back = plan
    arm.set_gripper(MAX_OPENING)
    arm.transfer(back.end, what=f"moving to pinch {obj}")
    arm.open_gripper(MAX_OPENING)
    arm.move_line(back.reversed(), *APPROACH)
    arm.expect_width(float(hi[2] - lo[2]))
    gap = arm.close_gripper()
    hand_t_world = np.linalg.inv(arm.tcp())
    st.held = Held(obj, sym.member, st.world.body_ids[obj], hand_t_world @ obj_pose(st, obj),
                   MAX_OPENING, sym, hand_t_world @ relook.in_hand(st, obj))  # fmt: skip
    if not arm.holds_something():
        raise SkillFailure(f"the fingers closed on nothing at the edge of {obj} (gap {gap:.3f} m)")
    start_obj, start_tcp = obj_pose(st, obj), arm.tcp()
    near = arm.sync(arm.near, gap=arm.gap())
    path = arm.line(arm.q(), pinch, np.array([0.0, 0.0, lift]), lambda _q: True,
                    what=f"lifting {obj}")  # fmt: skip
    check_lift(st, st.held, path)
    arm.move_line(path, *APPROACH)
    verify_lift(st, st.held, start_obj, start_tcp, before)


def place_edge(st: SimState, act: MacroAction) -> None:
    """``place-edge``: lower the edge-pinched board onto the table's edge where it was picked
    up, let go, back the hand off, and drag the board (`press_drag`, away from the edge
    first) until its footprint centre lies on the slot's position; verify it rests there."""
    obj, held, arm = act.grasp.obj, st.held, st.arm
    if held is None or held.obj != obj:
        raise SkillFailure(f"cannot place {obj}: the hand holds {held.obj if held else 'nothing'}")
    slots = {s.name: s for s in st.world.scene.slots}
    if act.support not in slots:
        raise GroundingError(f"place-edge puts a board on a table slot, not on {act.support}")
    before = snapshot(st, {obj})
    t = st.world.scene.type_of(obj)
    tcp = arm.tcp()
    if tcp[0, 3] > near_edge(st) - PAD_HALF:
        raise GroundingError(f"{obj} is not held over the table's edge")
    # the pinched end down to the table (the far end, drooping, lands first and the board
    # turns level in the pads): the lower finger then leaves its underside as the hand opens
    level = float(t.bbox.size[2]) / 2 + PLACE_DROP
    down = arm.line(arm.q(), tcp, np.array([0.0, 0.0, level - tcp[2, 3]]), lambda _q: True,
                    what=f"lowering {obj} onto the table's edge")  # fmt: skip
    arm.move_line(down, *APPROACH)
    arm.open_gripper(MAX_OPENING)
    st.held = None
    _let_go(st, obj, edge_depth(t) - PAD_IN)
    settle_objects(st)
    if st.estimator is not None:
        st.estimator.forget(obj)
    pose = st.estimate(obj)
    lo, hi = world_aabb(t.bbox, pose)
    offset = footprint_centre(t, pose) - (lo[:2] + hi[:2]) / 2
    goal = np.asarray(slots[act.support].position, dtype=float) - offset
    press_drag(st, obj, goal, y_first=False)
    verify_on(st, obj, act.support)
    moved = disturbed(st, before)
    if moved:
        raise SkillFailure(f"placing {obj} on {act.support} disturbed the scene: {moved}")


def _let_go(st: SimState, obj: str, deeper: float = 0.0) -> None:
    """With the fingers open around the board's overhang: lower the hand by one of
    `RELEASE_DROP` (the lower finger clear of the board's underside, the upper still above
    its top), then back it off along -x by one of `RELEASE_BACKOFF` and `deeper` (the pads
    clear of the board's end), the first pair the arm reaches."""
    arm = st.arm
    near = arm.sync(arm.near, gap=arm.gap())
    tried = []
    with ignoring(near, st.world.geom_ids[obj]):
        for drop_by, dist in itertools.product(RELEASE_DROP, RELEASE_BACKOFF):
            try:
                drop = arm.line(arm.q(), arm.tcp(), np.array([0.0, 0.0, -drop_by]),
                                near.is_valid, what="lowering the open hand")  # fmt: skip
                back = arm.line(drop.end, arm.kin.fk(drop.end), np.array([-dist - deeper, 0, 0]),
                                near.is_valid, what="backing off the board")  # fmt: skip
                break
            except GroundingError as exc:
                tried.append(str(exc))
        else:
            raise GroundingError("; ".join(dict.fromkeys(tried)))
    arm.move_line(drop, *APPROACH)
    arm.move_line(back, *APPROACH)


def slide_edge(st: SimState, act: MacroAction) -> None:
    """``slide-edge``: drag the board to the near edge, pinch its overhang, lift it."""
    obj = act.grasp.obj
    if st.held is not None:
        raise SkillFailure(f"cannot slide {obj} to the edge: the hand already holds {st.held.obj}")
    before = snapshot(st, {obj})
    drag_to_edge(st, obj)
    edge_pinch(st, act, before)


__all__ = ["drag_to_edge", "edge_pinch", "pinch_pose", "place_edge", "press_drag", "slide_edge"]
