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
* a cap on a body's top (a jar's lid), its fingers landing a little early on the body's
  shoulder beside it, the pads still on the cap (`shoulder_rest`): the guarded approach
  stops the hand there and the pads close on the cap, as long as the shoulder reaches less
  far out than the fingers open, by `SHOULDER_RELEASE` (letting go, the fingers open only a
  little before the hand rises: a shoulder under them keeps the jar wedged between them);
* a wrapped member (a handle, a body) lifts up to `EXTENDED_LIFT_LIMIT`, the moment about
  the grasp deciding beyond (`utamp_gym.affordances.hand.hold_refusal`; stock pots of
  1.57-2.22 kg were lifted by a lug, 2.56 kg pivoted).

Rim pinches of walls at least `hand.MIN_PINCH` thick (squeezed with the full force) are
calibrated in `utamp_gym.affordances.rim`.
"""

from __future__ import annotations

from utamp_gym.affordances.hand import (
    GRIPPER_OPENING,
    MIN_PAD_OVERLAP,
    OPEN_CLEARANCE,
    TOUCH,
    WRAP_CLEARANCE,
    finger_room,
)
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import OPPOSITE, axis_of
from utamp_gym.scene.shapes import WALL, rim_strip

#: kg a wrapped member carries in the extended domain (3/4 of the Panda's payload)
EXTENDED_LIFT_LIMIT = 2.25
#: m: the tallest cover over a body the open hand comes down around
LOW_COVER_LIMIT = 0.020
#: the tops a finger can go down into
OPEN_TOPS = ("open", "concave")
#: m early a finger may land on the shoulder of the body under a cap it closes on: the guarded
#: approach accepts a hand up to 10 mm short (`utamp_gym.sim.grasp_phases.APPROACH_STOP`), the
#: pads keeping `hand.MIN_PAD_OVERLAP` on the cap (as `rim.RIM_STOP_TOLERANCE` on a rim)
SHOULDER_TOLERANCE = 0.005
#: m the fingers, opened to their pre-grasp width, clear a cap's shoulder by (lid grasps of
#: v1 jars whose fingers land 0.5-3.5 mm early beside the lid: where the shoulder left them
#: 0.7 mm or more, 88 of 88 lifted and placed; at 0.6 mm 4 of 5 and at 0.5 mm or less 12 of
#: 13 stayed wedged between the opened fingers, lifted with the hand after the release)
SHOULDER_RELEASE = 0.001


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


def shoulder_rest(t: ObjectType, member: str, palm: str, finger: str) -> bool:
    """`member` is a cap on the body's top (a jar's lid) whose fingers, closing along
    `finger`'s axis, stop on the body's shoulder at most `SHOULDER_TOLERANCE` early, their
    pads keeping `hand.MIN_PAD_OVERLAP` on the cap, and the shoulder reaches beyond the cap
    at least `SHOULDER_RELEASE` less far than the fingers open (`hand.OPEN_CLEARANCE` a
    side, less if the 8 cm do not allow it), so that they let go of it."""
    m, body = t.members[member], t.body
    if palm != "on" or m.kind == "body" or m.box.min[2] < body.box.max[2] - 1e-6:
        return False  # not a cap sitting on the body's top
    ax = axis_of(finger)
    cap, below = float(m.box.size[ax]), float(body.box.size[ax])
    opening = min(OPEN_CLEARANCE, max(GRIPPER_OPENING - cap, 0.0) / 2)
    if (below - cap) / 2 > opening - SHOULDER_RELEASE + 1e-9:
        return False  # the opened fingers would not clear the shoulder
    room = finger_room(t, member, palm, finger)
    return all(
        short <= TOUCH
        or (by == body.name and short <= SHOULDER_TOLERANCE and overlap >= MIN_PAD_OVERLAP)
        for short, by, overlap in zip(room.shortfall, room.stopped_by, room.overlap, strict=True)
    )


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


__all__ = [
    "EXTENDED_LIFT_LIMIT",
    "LOW_COVER_LIMIT",
    "SHOULDER_RELEASE",
    "SHOULDER_TOLERANCE",
    "low_cover",
    "lug_wall",
    "shoulder_rest",
]
