"""What a table slot holds: an object whose footprint fits inside the slot's region, at a spot
that leaves every member within the arm's reach.

A slot stands for the table top in its region (`symbolic.problem`), and the symbolic state
knows one stack per slot. So an object stands in a slot only inside the region (within the
workspace): hanging over a neighbour's region it would take room the symbolic state gives
to the neighbour's stack. A tray 45 cm long parked in a 38 cm side slot did just that, and a
spatula's handle reaching into the slot left room only where the tray's far handle lay
0.83 m from the robot's base, out of reach (`procedural-v1/train/0081`).

Both sides use this module: the rules grant a placement on a slot only to an object the slot
`admits` (`symbolic.problem.instantiate_affordances`), and the placement sets an object down
only at one of the same `slot_spots` where it lies inside the `usable_region` with every
member in reach (`beyond_reach_cm` 0; `sim.placement`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from functools import lru_cache
from typing import NamedTuple

from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import SIDES, Box, axis_of
from utamp_gym.scene.model import STANDING_PART, Scene, Slot

#: m between two spots of a slot: its position, then a grid this fine over its region
SPOT_STEP = 0.03
#: m from the robot's base (horizontal) to a member's centre that the hand reaches from above
#: and lifts from (the procedural layout's `REACH`; tests/test_robot_kinematics.py: the TCP
#: pointing down reaches it up to 35 cm above the table). A tray set down square in a far
#: corner put its far handle 0.89 m out, and no arm reached it again. At 0.78 m a plate's rim
#: set down 0.78 m out was reached but could not be lifted
MEMBER_REACH = 0.74


def usable_region(scene: Scene, slot: Slot) -> Box:
    """The slot's region within the workspace, on the table top (z = 0)."""
    (rx0, ry0, _), (rx1, ry1, _) = slot.region
    (wx0, wy0, _), (wx1, wy1, _) = scene.workspace
    return Box((max(rx0, wx0), max(ry0, wy0), 0.0), (min(rx1, wx1), min(ry1, wy1), 0.0))


def slot_spots(scene: Scene, slot: Slot) -> tuple[tuple[float, float], ...]:
    """The slot's position, then every point `SPOT_STEP` apart on a grid through it inside
    the usable region, nearest the position first (ties: nearer the robot first)."""
    return _spots(usable_region(scene, slot), (float(slot.position[0]), float(slot.position[1])))


def _steps(p: float, lo: float, hi: float, n: int) -> list[tuple[int, float]]:
    """(i, p + i * SPOT_STEP) for i in -n..n, ascending, of the points within [lo, hi]."""
    out = []
    for i in range(-n, n + 1):
        v = p + i * SPOT_STEP
        if lo - 1e-9 <= v <= hi + 1e-9:
            out.append((i, v))
    return out


def _grid_size(region: Box) -> int:
    """How many `SPOT_STEP`s the grid reaches out from the position along each axis."""
    size = math.hypot(region.max[0] - region.min[0], region.max[1] - region.min[1])
    return int(size / SPOT_STEP) + 1


@lru_cache(maxsize=64)
def _spots(region: Box, position: tuple[float, float]) -> tuple[tuple[float, float], ...]:
    px, py = position
    n = _grid_size(region)
    xs = _steps(px, region.min[0], region.max[0], n)
    ys = _steps(py, region.min[1], region.max[1], n)
    # a grid point lies in the region when each of its coordinates does: the axes' points in
    # ascending order, i outer, j inner (the stable sort keeps this order between ties)
    spots = [
        (round(math.hypot(i, j) * SPOT_STEP, 6), x, (x, y)) for i, x in xs for j, y in ys if i or j
    ]
    spots.sort(key=lambda s: (s[0], s[1]))
    return ((px, py), *(s[2] for s in spots))


def beyond_reach_cm(centres: Iterable[tuple[float, float]]) -> float:
    """How far (cm, rounded) the farthest of some member centres (x, y) lies beyond
    `MEMBER_REACH` of the robot's base (the world origin); 0 within it."""
    far = max(math.hypot(x, y) for x, y in centres)
    return max(0.0, round(100 * (far - MEMBER_REACH)))


def footprint_size(box: Box, part: str) -> tuple[float, float]:
    """(x, y) extent on the table of an object with bounding box `box` resting on `part`.

    Objects keep their yaw; on ``under`` or ``on`` the footprint is the box's own; on a side
    the object has tipped over that side's edge, so its height lies along the side's axis."""
    lo, hi = box
    sx, sy, sz = float(hi[0] - lo[0]), float(hi[1] - lo[1]), float(hi[2] - lo[2])
    axis = _AXIS[part]
    if axis == 2:
        return sx, sy
    return (sz, sy) if axis == 0 else (sx, sz)


_AXIS = {side: axis_of(side) for side in SIDES}


class Footprint(NamedTuple):
    """What `admits` asks of an object type resting on a part: the footprint's extent and,
    for an object kept upright or upside down, the footprint's x and y bounds about its
    centre and its members' centres as offsets from it (None for a side)."""

    width: float
    depth: float
    fx: tuple[float, float, float] | None  # (min x, max x, centre x) of the footprint
    fy: tuple[float, float, float] | None
    members: tuple[tuple[float, float], ...]

    @classmethod
    def of(cls, t: ObjectType, part: str) -> Footprint:
        bbox = t.bbox
        w, d = footprint_size(bbox, part)
        upright = part == STANDING_PART["upright"]
        if not upright and part != STANDING_PART["inverted"]:
            return cls(w, d, None, None, ())
        box = bbox if upright else bbox.flipped()
        cx, cy = box.center_xy
        sign = 1.0 if upright else -1.0  # a half turn about x mirrors y
        centres = [m.box.center_xy for m in t.members.values()]  # plain floats: no numpy here
        members = tuple((mx - cx, sign * my - cy) for mx, my in centres)
        return cls(w, d, (box.min[0], box.max[0], cx), (box.min[1], box.max[1], cy), members)


def admits(scene: Scene, slot: Slot, t: ObjectType, part: str) -> bool:
    """Whether an object of type `t` resting on `part` can stand in the slot: at one of its
    `slot_spots` (footprint centred there, the object square to the table) it lies inside
    the usable region with every member's centre in reach (`beyond_reach_cm` 0).

    Pick and place keep an object upright or upside down, so it rests on ``under`` or ``on``;
    for a side (an object tipped over, which no action does) only the footprint's size counts.
    """
    return fits(usable_region(scene, slot), slot, Footprint.of(t, part))


def fits(region: Box, slot: Slot, fp: Footprint) -> bool:
    """`admits` for a slot's `usable_region` and a type's `Footprint` (each made once when
    many slots and types are paired: `symbolic.problem.instantiate_affordances`)."""
    (rx0, ry0, _), (rx1, ry1, _) = region
    if fp.width > rx1 - rx0 + 1e-6 or fp.depth > ry1 - ry0 + 1e-6:
        return False
    if fp.fx is None or fp.fy is None:
        return True
    members = fp.members
    fx, fy = (*fp.fx, rx0, rx1), (*fp.fy, ry0, ry1)
    # `slot_spots` in another order: the position, then the grid points in the region. The
    # footprint lies inside the region (`Box.contains_xy`, tol 1e-6) when it does along x
    # and along y, so of the grid only the points whose x and y both pass are tried.
    px, py = float(slot.position[0]), float(slot.position[1])
    if _inside(px, *fx) and _inside(py, *fy) and _reached(px, py, members):
        return True
    n = _grid_size(region)
    xs = [x for _, x in _steps(px, rx0, rx1, n) if _inside(x, *fx)]
    ys = [y for _, y in _steps(py, ry0, ry1, n) if _inside(y, *fy)]
    return any(_reached(x, y, members) for x in xs for y in ys)


def _reached(x: float, y: float, members: tuple[tuple[float, float], ...]) -> bool:
    """Whether every member (offsets from the footprint's centre) is in reach with the
    footprint centred on (x, y)."""
    return beyond_reach_cm([(x + mx, y + my) for mx, my in members]) == 0


def _inside(v: float, lo: float, hi: float, c: float, r_lo: float, r_hi: float) -> bool:
    """Along one axis, whether the footprint [lo, hi] of a box centred on `c`, moved to
    centre on `v`, lies within the region [r_lo, r_hi] (`Box.contains_xy`, tol 1e-6)."""
    return r_lo - 1e-6 <= v + lo - c and v + hi - c <= r_hi + 1e-6


__all__ = [
    "MEMBER_REACH",
    "SPOT_STEP",
    "Footprint",
    "admits",
    "beyond_reach_cm",
    "fits",
    "footprint_size",
    "slot_spots",
    "usable_region",
]
