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


#: a body too wide for the hand whose top is open or concave is pinched at its wall: the
#: strip of wall `RIM_BAND` deep below the rim (at most the wall above the floor, less
#: `RIM_FLOOR_GAP`), `RIM_HALF` wide at most (`RIM_HALF_FRACTION` of the radius), on the
#: side the first finger part names (``front``: the wall at +x)
RIM_BAND, RIM_FLOOR_GAP, RIM_HALF, RIM_HALF_FRACTION = 0.025, 0.005, 0.04, 0.4
WRAP_LIMIT = 0.074  # m: the widest body the open hand closes around (8 cm less 3 mm a side)
RIM_SIDES = {"front": (0, 1), "back": (0, -1), "left": (1, 1), "right": (1, -1)}


def rim_strip(t: ObjectType, member: str, palm: str, finger: str) -> Box | None:
    """The wall strip a grasp of the body `member` from above (`palm` ``on``) pinches,
    fingers along `finger`'s axis, when the body is wider than `WRAP_LIMIT` along it and
    its top is open or concave: the wall on `finger`'s side (its thickness: the body's face
    less the top's usable size, halved). None for any other grasp (decoded as before)."""
    m = t.members[member]
    if m.kind != "body" or palm != "on" or finger not in RIM_SIDES:
        return None
    top = t.parts["on"]
    lo, hi = m.box.min, m.box.max
    if top.shape not in ("open", "concave") or hi[2] < t.bbox.max[2] - 1e-9:
        return None
    ax, sign = RIM_SIDES[finger]
    if hi[ax] - lo[ax] <= WRAP_LIMIT + 1e-9:
        return None
    size = (
        top.size if top.size is not None else (hi[0] - lo[0] - 2 * WALL, hi[1] - lo[1] - 2 * WALL)
    )
    wall = (hi[ax] - lo[ax] - size[ax]) / 2
    if wall <= 0:
        return None
    concave = top.shape == "concave"
    floor = lo[2] + floor_thickness(concave, hi[2] - lo[2])
    depth = min(RIM_BAND, hi[2] - floor - RIM_FLOOR_GAP)
    if depth <= 0:
        return None
    lat = 1 - ax
    mid = (lo[lat] + hi[lat]) / 2
    half = min(RIM_HALF, RIM_HALF_FRACTION * (hi[lat] - lo[lat]) / 2)
    slo, shi = [0.0, 0.0, hi[2] - depth], [0.0, 0.0, hi[2]]
    slo[ax], shi[ax] = (hi[ax] - wall, hi[ax]) if sign > 0 else (lo[ax], lo[ax] + wall)
    slo[lat], shi[lat] = mid - half, mid + half
    return Box(tuple(slo), tuple(shi))


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
    "RIM_BAND",
    "RIM_WALL",
    "WALL",
    "WRAP_LIMIT",
    "floor_thickness",
    "loop_axis",
    "rim_strip",
    "touch_axis",
]
