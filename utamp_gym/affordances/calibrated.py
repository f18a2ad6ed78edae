"""Grasps the extended domain (``utamp2x``) grants beyond the paper's rules, calibrated in
physics (`benchmarks/grasp_coverage.py` tries every grasp from above the rules forbid, on
train instances of procedural v1). They decide from geometry and mass alone:

* a lug beside an open-topped body's wall (a stock pot's, a mug's handle), the fingers
  closing across the lug and the wall: the finger on the wall's side goes down inside the
  open body, and the pads pinch lug and wall together (`lug_wall`; the paper's rules see the
  wall as a sibling blocking that finger; 80 of 80 such v1 stock-pot grasps held, and the 5
  v1 mugs narrow enough to wrap); the hand may come to rest on that body's rim up to
  `hand.HAND_REST_TOLERANCE` above its target (10 of 10 such v1 mugs lifted);
* a body under a low cover (a jar's lid) no wider than the hand clears: the fingers come
  down around the cover and close on the body below it (`low_cover`; lids up to 19.9 mm
  tall let the hand down, 20.4 mm stopped it);
* a wrapped member (a handle, a body) lifts up to `EXTENDED_LIFT_LIMIT`, the moment about
  the grasp deciding beyond (`utamp_gym.affordances.hand.hold_refusal`; stock pots of
  1.57-2.22 kg were lifted by a lug, 2.56 kg pivoted).

Rim pinches of walls at least `hand.MIN_PINCH` thick (squeezed with the full force) are
calibrated in `utamp_gym.affordances.rim`.
"""

from __future__ import annotations

from utamp_gym.affordances.hand import GRIPPER_OPENING, OPEN_CLEARANCE, WRAP_CLEARANCE
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import OPPOSITE, axis_of
from utamp_gym.scene.shapes import WALL, rim_strip

#: kg a wrapped member carries in the extended domain (3/4 of the Panda's payload)
EXTENDED_LIFT_LIMIT = 2.25
#: m: the tallest cover over a body the open hand comes down around
LOW_COVER_LIMIT = 0.020
#: the tops a finger can go down into
OPEN_TOPS = ("open", "concave")


def low_cover(t: ObjectType, member: str, palm: str, other: str) -> bool:
    """`other` covers the body `member` from above but is low and narrow enough for the
    open hand to come down around it and close on the body below (a jar's lid)."""
    if palm != "on" or t.members[member].kind != "body":
        return False
    box, cover = t.members[member].box, t.members[other].box
    if cover.min[2] < box.max[2] - 1e-6 or cover.size[2] > LOW_COVER_LIMIT + 1e-9:
        return False  # not a cap sitting on the body's top, or too tall
    limit = GRIPPER_OPENING - 2 * WRAP_CLEARANCE
    return all(cover.size[i] <= limit + 1e-9 for i in (0, 1))


def lug_wall(t: ObjectType, member: str, palm: str, side: str, other: str) -> bool:
    """The sibling `other` beside `member`'s `side` is an open-topped body's wall standing
    above it, thinner than the open fingers' clearance, so the finger on that side goes
    down inside the body and the pads pinch the member and the wall together."""
    m = t.members[member]
    if palm != "on" or m.kind != "handle" or other != t.body.name:
        return False
    if t.parts["on"].shape not in OPEN_TOPS or t.body.box.max[2] < m.box.max[2] + 1e-9:
        return False
    ax = axis_of(side)
    strip = rim_strip(t, other, "on", OPPOSITE[side])  # the wall facing the member
    if strip is not None:
        wall = float(strip.size[ax])
    else:  # a body the hand could wrap (a mug's): its wall is what its open top leaves
        top, face = t.parts["on"].size, t.body.box.size[ax]
        wall = (face - (top[ax] if top is not None else face - 2 * WALL)) / 2
        if wall <= 0:
            return False
    return wall < OPEN_CLEARANCE and m.box.size[ax] + wall <= GRIPPER_OPENING - 2 * WRAP_CLEARANCE


__all__ = ["EXTENDED_LIFT_LIMIT", "LOW_COVER_LIMIT", "low_cover", "lug_wall"]
