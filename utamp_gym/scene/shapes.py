"""How attributes are realised as shapes: one reading shared by the simulator and the rules.

`sim.bodies` builds bodies by these conventions and `affordances.hand` reasons about the same
material: a hollow body (an open or concave top) has a floor `FLOOR` thick (`CONCAVE_FLOOR`
under a concave top; at most a quarter of its height) under walls as thick as the rim its
top's `size` leaves (`WALL`, `RIM_WALL` by default); a handle beside the body (touching it
along a horizontal axis) that leaves a finger-sized opening is a loop of `BAR`-thick bars,
gripped at its outer bar (`sim.decode` puts the fingers there); a handle apart from the body
is a bar on posts; anything else is solid.
"""

from __future__ import annotations

from utamp_gym.scene.catalogue import Member, ObjectType
from utamp_gym.scene.geometry import Box

WALL = 0.004  # m, default wall thickness of hollow (open-top) bodies
FLOOR = 0.008  # m, floor thickness of hollow bodies
RIM_WALL = 0.003  # m, default flared rim thickness of concave bodies
CONCAVE_FLOOR = 0.005  # m, floor thickness of concave bodies
BAR = 0.008  # m, bar thickness of a loop handle
LOOP_OPENING = (0.015, 0.03)  # m, smallest (outward, vertical) opening of a loop handle


def floor_thickness(concave: bool, height: float) -> float:
    """The floor of a hollow body of `height` (an open top's, or a concave top's)."""
    return min(CONCAVE_FLOOR if concave else FLOOR, height / 4)


def touch_axis(a: Box, b: Box, tol: float = 1e-6) -> tuple[int, int] | None:
    """(axis, sign) if box `a` lies beside `b` along one axis (touching or apart), else None."""
    for ax in range(3):
        others = [i for i in range(3) if i != ax]
        if not all(a.min[i] < b.max[i] and b.min[i] < a.max[i] for i in others):
            continue
        if a.min[ax] >= b.max[ax] - tol:
            return ax, 1
        if a.max[ax] <= b.min[ax] + tol:
            return ax, -1
    return None


def loop_axis(t: ObjectType, m: Member) -> tuple[int, int] | None:
    """(axis, sign) pointing out of the body if `m` is a loop handle, else None."""
    if m.kind != "handle" or m.geom != "box":
        return None
    side = touch_axis(m.box, t.body.box)
    if side is None or side[0] == 2:
        return None
    ax, sign = side
    gap = (m.box.min[ax] - t.body.box.max[ax]) if sign > 0 else (t.body.box.min[ax] - m.box.max[ax])
    if gap > 1e-6:
        return None
    out_len = m.box.max[ax] - m.box.min[ax]
    height = m.box.max[2] - m.box.min[2]
    if out_len - BAR >= LOOP_OPENING[0] and height - 2 * BAR >= LOOP_OPENING[1]:
        return side
    return None


__all__ = [
    "BAR",
    "CONCAVE_FLOOR",
    "FLOOR",
    "LOOP_OPENING",
    "RIM_WALL",
    "WALL",
    "floor_thickness",
    "loop_axis",
    "touch_axis",
]
