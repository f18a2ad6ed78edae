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
   overhangs the near edge by `OVERHANG`; where it lagged the hand (a few centimetres), a
   second drag of the measured error corrects it (`DRAG_ROUNDS`). The sweep must be clear of
   every other object.
2. Pinch (`edge_pinch`): the hand approaches horizontally from outside the table (its z
   along +x, towards the robot), the fingers open `MAX_OPENING` and closing vertically on the
   board's thickness, the pads `PAD_IN` inside the board's back end, clear of the table's
   edge; it closes and lifts, and the lift is measured as a pick's (`grasp_phases.verify_lift`).

The action's grasp symbols are the board's body, palm ``back`` (the side facing the near edge at
the scene's yaw) and fingers ``on``/``under``; after it the hand holds the board.
"""

from __future__ import annotations

import numpy as np

from utamp_gym.affordances.edge import BASE_CLEARANCE, EDGE_Y, OVERHANG, PAD_IN
from utamp_gym.errors import GroundingError
from utamp_gym.sim import relook
from utamp_gym.sim.control import ignoring
from utamp_gym.sim.decode import MAX_OPENING, TIP_BELOW_TCP, MacroAction, world_aabb
from utamp_gym.sim.grasp_phases import APPROACH, check_lift, verify_lift
from utamp_gym.sim.measure import (
    Held,
    SimState,
    SkillFailure,
    lift_height,
    obj_pose,
    settle_objects,
    snapshot,
)

PRESS = 0.006  # m the fingertips are commanded below the board's top while dragging
OVERHANG_TOL = 0.008  # m: an overhang this far off after the drags fails the action
PAD_HALF = 0.00925  # m: half the pads' length along the approach
PAD_CLEAR = 0.003  # m the pads stay short of the table's edge
PINCH_BACKOFF = (0.06, 0.04, 0.03)  # m the horizontal approach starts back from the pinch
DRAG = (0.12, 0.3)  # m/s, m/s^2
DRAG_ROUNDS = 2
SWEEP_MARGIN = 0.01  # m another object's footprint must clear the dragged board by
PRESS_ABOVE = 0.10  # m above the press point the hand comes down from
HAND_DOWN = np.diag([1.0, -1.0, -1.0])


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


def _sweep_clear(st: SimState, obj: str, lo: np.ndarray, hi: np.ndarray, shift: np.ndarray) -> str:
    """The first other object whose footprint the board meets when moved by `shift` (first
    along y, then along x), or ""."""
    a_lo, a_hi = lo[:2].copy(), hi[:2].copy()
    dy, dx = np.array([0.0, shift[1]]), np.array([shift[0], 0.0])
    mid_lo, mid_hi = a_lo + dy, a_hi + dy
    end_lo, end_hi = mid_lo + dx, mid_hi + dx
    boxes = [
        (np.minimum(a_lo, mid_lo), np.maximum(a_hi, mid_hi)),
        (np.minimum(mid_lo, end_lo), np.maximum(mid_hi, end_hi)),
    ]
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


def drag_to_edge(st: SimState, obj: str) -> None:
    """Press `obj` from above and drag it until its back end overhangs the near edge by
    `OVERHANG` (see the module docstring); raises `GroundingError` / `SkillFailure`."""
    arm, geoms = st.arm, st.world.geom_ids[obj]
    lo, hi = _aabb(st, obj)
    edge = near_edge(st)
    tried = []
    for y in target_y(lo, hi):
        mid = (lo + hi) / 2
        shift = np.array([edge - OVERHANG - lo[0], y - mid[1]])
        other = _sweep_clear(st, obj, lo, hi, shift)
        if other:
            tried.append(f"y {y:+.2f}: {other} is in the way")
            continue
        press = _press_pose(mid[0], mid[1], hi[2])
        above = press.copy()
        above[2, 3] += PRESS_ABOVE
        arm.set_gripper(0.0)
        arm.close_gripper(max_s=0.4)
        near = arm.sync(arm.near, gap=arm.gap())
        try:
            with ignoring(near, geoms):
                q = next(arm.ik_solutions(above, near.is_valid), None)
                if q is None:
                    raise GroundingError("IK infeasible: no configuration above the board")
                down = arm.line(q, above, np.array([0.0, 0.0, -PRESS_ABOVE]), near.is_valid,
                                what=f"pressing {obj}")  # fmt: skip
                side = arm.line(down.end, press, np.array([0.0, shift[1], 0.0]), near.is_valid,
                                what=f"dragging {obj} sideways")  # fmt: skip
                turn = press.copy()
                turn[1, 3] += shift[1]
                back = arm.line(side.end, turn, np.array([shift[0], 0.0, 0.0]), near.is_valid,
                                what=f"dragging {obj} to the edge")  # fmt: skip
        except GroundingError as exc:
            tried.append(f"y {y:+.2f}: {exc}")
            continue
        arm.transfer(q, what=f"moving over {obj}")
        arm.move_line(down, *APPROACH)
        arm.move_line(side, *DRAG)
        arm.move_line(back, *DRAG)
        hand = turn.copy()
        hand[0, 3] += shift[0]
        for _ in range(DRAG_ROUNDS - 1):
            _correct(st, obj, hand, np.array([edge - OVERHANG, y]))
        up = arm.line(arm.q(), hand, np.array([0.0, 0.0, PRESS_ABOVE]), lambda _q: True,
                      what="the retreat")  # fmt: skip
        arm.move_line(up, *APPROACH)
        arm.open_gripper(MAX_OPENING, max_s=0.3)
        settle_objects(st)
        _check_overhang(st, obj, edge)
        return
    raise GroundingError(f"cannot slide {obj} to the table's edge ({'; '.join(tried)})")


def _correct(st: SimState, obj: str, hand: np.ndarray, want: np.ndarray) -> None:
    """Drag the pressed board again by the error of its back end and middle (it lags the
    hand); `hand` (the commanded press pose) is updated."""
    if st.estimator is not None:
        st.estimator.forget(obj)
    lo, hi = _aabb(st, obj)
    err = np.array([want[0] - lo[0], want[1] - (lo[1] + hi[1]) / 2, 0.0])
    if np.abs(err).max() < 1e-3:
        return
    arm = st.arm
    near = arm.sync(arm.near, gap=arm.gap())
    with ignoring(near, st.world.geom_ids[obj]):
        path = arm.line(arm.q(), hand, err, near.is_valid, what=f"dragging {obj} on")
    arm.move_line(path, DRAG[0] / 2, DRAG[1])
    hand[:3, 3] += err


def _check_overhang(st: SimState, obj: str, edge: float) -> None:
    if st.estimator is not None:
        st.estimator.forget(obj)
    lo, _ = world_aabb(st.world.scene.type_of(obj).bbox, obj_pose(st, obj))
    over = edge - float(lo[0])
    if abs(over - OVERHANG) > OVERHANG_TOL:
        raise SkillFailure(
            f"{obj} overhangs the table's edge by {over * 100:.1f} cm after the slide "
            f"(wanted {OVERHANG * 100:.1f} cm)"
        )


def pinch_pose(lo: np.ndarray, hi: np.ndarray, roll: float, edge: float) -> np.ndarray:
    """TCP pose pinching the overhang of a board with world extent `lo`..`hi`: `PAD_IN`
    inside its back end (or less, the pads `PAD_CLEAR` short of the table's edge at x =
    `edge`), at its mid-height, approaching along +x, the fingers closing vertically (`roll`
    +1 or -1: which way up the hand is)."""
    z = np.array([1.0, 0.0, 0.0])
    x = np.array([0.0, roll, 0.0])
    out = np.eye(4)
    out[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    x = min(lo[0] + PAD_IN, edge - PAD_HALF - PAD_CLEAR)
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
    tried = []
    near = arm.sync(arm.near, gap=MAX_OPENING)
    plan = None
    with ignoring(near, geoms):
        for roll in (1.0, -1.0):
            pinch = pinch_pose(lo, hi, roll, near_edge(st))
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


def slide_edge(st: SimState, act: MacroAction) -> None:
    """``slide-edge``: drag the board to the near edge, pinch its overhang, lift it."""
    obj = act.grasp.obj
    if st.held is not None:
        raise SkillFailure(f"cannot slide {obj} to the edge: the hand already holds {st.held.obj}")
    before = snapshot(st, {obj})
    drag_to_edge(st, obj)
    edge_pinch(st, act, before)


__all__ = ["drag_to_edge", "edge_pinch", "pinch_pose", "slide_edge"]
