"""Rim pinches: the grasps the extended domain (``utamp2x``) adds to the paper's rules.

A real Panda takes a bowl, a pot without a usable handle or a plate by pinching its wall at
the rim from above: one finger inside, one outside, the pads straddling the wall. The
paper's rules (`utamp_gym.affordances.rules`) refuse most of these: a wall thinner than
`hand.MIN_PINCH` was squirted out of the pads by the full 70 N squeeze, and an edge grasp
carries at most 0.5 kg. The simulator now pinches a wall thinner than `hand.MIN_PINCH` with
`PINCH_FORCE` and reads a thin wall as held (`utamp_gym.sim.control.ArmDriver.expect_width`),
and these rules grant what was measured to hold (`benchmarks/grasp_coverage.py`). They
decide from geometry and mass alone, never from a family or a type name:

* the member is an edge realised by the body's own wall or rim, reaching the body's top
  (a rim), taken from above (palm on ``on``) with the object standing on its ``under``;
* no other member stands over it, and the fingers close across its thickness (the smaller
  horizontal extent): at least `RIM_MIN_WIDTH`, within the hand's opening;
* each finger reaches its place beside the wall (`hand.finger_room`): a finger may land on
  the object's own body up to `RIM_STOP_TOLERANCE` early (a plate's well beside its rim:
  the approach guard stops the hand 1 cm short at most, `sim.grasp_phases.APPROACH_STOP`) while
  its pad keeps `hand.MIN_PAD_OVERLAP` on the rim (calibrated: on a sibling as well, a
  stock pot's lug just below the rim: 6 of 6 v1 pots within the torque limit lifted); the
  hand above comes down freely;
* the wall stands upright: its foot (the ``under`` surface) lies at most `FLARE_LIMIT`
  inside its rim;
* the object weighs at most `RIM_LIFT_LIMIT` and the moment of its weight about the pinch
  stays within `THIN_TORQUE_LIMIT`, for a wall squeezed with the reduced `PINCH_FORCE`; a
  wall at least `hand.MIN_PINCH` thick, squeezed with the full force, carries
  `calibrated.EXTENDED_LIFT_LIMIT` and, where its rim takes the whole pad, the moment the
  pads bear on it: `rim_couple_limit` of its thickness (the squeeze's share and the pads'
  friction couple across the rim; a thinner rim bears less).
"""

from __future__ import annotations

import math

from utamp_gym.affordances.calibrated import EXTENDED_LIFT_LIMIT
from utamp_gym.affordances.edge import EDGE_COUPLE_SHARE, GRIP_FORCE, PAD_FRICTION
from utamp_gym.affordances.hand import (
    GRIPPER_OPENING,
    MIN_PAD_OVERLAP,
    MIN_PINCH,
    PAD_HEIGHT,
    PAD_WIDTH,
    TORQUE_LIMIT,
    TOUCH,
    G,
    finger_room,
    hand_blocker,
)
from utamp_gym.affordances.solids import centre_of_mass, realised_by_body, stand_refusal
from utamp_gym.affordances.why import REFUSED, Refusal
from utamp_gym.scene.catalogue import Member, ObjectType
from utamp_gym.scene.geometry import axis_of
from utamp_gym.scene.shapes import rim_strip

RIM_MIN_WIDTH = 0.001  # m: the thinnest wall pinched (steel bowls of 1.1 mm held)
#: m: the thinnest wall the calibrated rules pinch (0.8-0.9 mm pot walls were lifted: 7 of
#: 7 v1 saucepan and stock-pot pinches within the torque limit), if it bows across the pads
#: less than it is thick (`wall_bow`)
CALIBRATED_MIN_WIDTH = 0.0008
RIM_STOP_TOLERANCE = 0.005  # m a finger may land early on the object's own body
RIM_LIFT_LIMIT = 1.1  # kg a rim pinch carries (plates of 1.05 kg were lifted and placed)
#: N m about the pinch for a wall thinner than `hand.MIN_PINCH`, squeezed with the reduced
#: force (the heaviest bowl measured, 0.57 N m, held)
THIN_TORQUE_LIMIT = 0.6
#: N m the calibrated rules allow a thin wall (v1 pots pinched at the rim: every one up to
#: 0.66 N m lifted, from 0.72 N m they slipped or pivoted)
CALIBRATED_THIN_TORQUE_LIMIT = 0.665
#: m a wall may slope out from its foot to its rim: flat pads meet a flared wall (a frying
#: pan's) along a line and it pivots between them (6 of 6 light frying pans fell)
FLARE_LIMIT = 0.003
#: m: a rim this tall takes the whole pad (`hand.PAD_HEIGHT` and 2 mm) and bears
#: `rim_couple_limit` of its thickness; a lower one `hand.TORQUE_LIMIT` (sheet pans with
#: 19.9 mm rims slipped at 2.1 N m, 22-26 mm ones 11.5-12.3 mm thick held 1.9-2.1 N m)
FULL_PAD_RIM = PAD_HEIGHT + 0.002
#: N m the squeeze's share bears about the pinch of such a rim, to which the pads' friction
#: couple across the rim's thickness adds ``GRIP_FORCE * EDGE_COUPLE_SHARE * PAD_FRICTION``
#: per metre of it (`rim_couple_limit`, as `utamp_gym.affordances.edge.edge_torque_limit`):
#: v1 trays pinched at a side rim 16.6-19.7 mm thick held 2.32-2.48 N m, rims 13.5-15.2 mm
#: thick slipped from 2.41 N m; a sheet pan's 8.2 mm rim pivoted 15 deg at 2.12 N m
#: (procedural-v1/test-families/0040, 1.94 N m by the couple), where the flat 2.3 N m the
#: trays' side rims held had granted it
RIM_COUPLE_BASE = 1.38
PINCH_FORCE = 30.0  # N: `utamp_gym.sim.control.PINCH_FORCE`, for a wall below `MIN_PINCH`


def _covered(t: ObjectType, member: str) -> str | None:
    """A sibling member over the rim (reaching above its top where it lies)."""
    box = t.members[member].box
    for name, m in t.members.items():
        other = m.box
        if name == member or other.max[2] <= box.max[2] + 1e-9:
            continue
        if all(
            box.min[i] < other.max[i] - 1e-9 and other.min[i] < box.max[i] - 1e-9 for i in (0, 1)
        ):
            return name
    return None


#: the name of the wall strip a body's pinch takes, as a member of the type it is judged on
STRIP = "rim-strip"


def _strip_type(t: ObjectType, member: str, palm: str, f1: str) -> ObjectType | None:
    """`t` with the body's wall strip (`utamp_gym.scene.shapes.rim_strip`) as an edge member
    `STRIP`, if a grasp of the body `member` is decoded as a pinch of it, else None."""
    strip = rim_strip(t, member, palm, f1)
    if strip is None:
        return None
    return t._replace(members={**t.members, STRIP: Member(STRIP, "edge", strip)})


def rim_pinch_refusal(
    t: ObjectType,
    member: str,
    palm: str,
    f1: str,
    f2: str,
    why: bool = True,
    calibrated: bool = True,
) -> Refusal | None:
    """Why the hand cannot pinch `member` as a rim from above and lift the object by it
    (None: it can; `REFUSED` if not `why`). A body too wide for the hand with an open top
    is judged by the wall strip the decoder pinches (`utamp_gym.scene.shapes.rim_strip`).
    See the module docstring; not `calibrated`: a thick wall carries only `RIM_LIFT_LIMIT`
    and `hand.TORQUE_LIMIT`, as before issue #39's calibration."""
    if t.members[member].kind == "body":
        strip = _strip_type(t, member, palm, f1)
        if strip is None:
            values = {"member": member, "what": "a body the hand wraps, or without an open top"}
            return Refusal("rim", values) if why else REFUSED
        return _rim_refusal(strip, STRIP, palm, f1, f2, why, calibrated)
    return _rim_refusal(t, member, palm, f1, f2, why, calibrated)


def _rim_refusal(
    t: ObjectType,
    member: str,
    palm: str,
    f1: str,
    f2: str,
    why: bool = True,
    calibrated: bool = True,
) -> Refusal | None:

    def no(rule: str, **values: object) -> Refusal:
        return Refusal(rule, {"member": member, **values}) if why else REFUSED

    m = t.members[member]
    if not t.movable:
        return Refusal("fixed", {"type": t.name}) if why else REFUSED
    if palm != "on" or m.kind != "edge" or not realised_by_body(t, m):
        return no("rim", what=f"a {m.kind} taken with the palm on {palm}")
    if m.box.max[2] < t.body.box.max[2] - 1e-6:
        return no("rim", what="an edge below the body's top")
    under = t.parts["under"]
    if under.shape not in ("flat", "open") or under.food_surface:
        return no("rim", what=f"on an object whose under ({under.shape}) never stands")
    stands = stand_refusal(t, "under", why)
    if stands is not None:
        return stands
    ax = axis_of(f1)
    body = t.body.box
    if under.size is not None and ax != 2 and body.min[2] <= t.bbox.min[2] + 1e-9:
        flare = (body.size[ax] - under.size[ax]) / 2  # the wall slopes out by this
        if flare > FLARE_LIMIT:
            return no("rim-flare", flare=flare, limit=FLARE_LIMIT)
    other = _covered(t, member)
    if other is not None:
        return no("covered", palm=palm, other=other)  # a sibling over the rim
    if ax == 2:
        return no("rim", what="with the fingers along the approach")
    width, lateral = float(m.box.size[ax]), float(m.box.size[1 - ax])
    if width > lateral + 1e-9:
        return no("rim-across", width=width, lateral=lateral, fingers=f"{f1}/{f2}")
    thinnest = CALIBRATED_MIN_WIDTH if calibrated else RIM_MIN_WIDTH
    if not thinnest - 1e-9 <= width <= GRIPPER_OPENING:
        limits = (thinnest, GRIPPER_OPENING)
        return no("rim-width", width=width, limits=limits, fingers=f"{f1}/{f2}")
    if width < RIM_MIN_WIDTH - 1e-9 and t.body.geom == "cylinder":
        bow = wall_bow(float(body.size[ax]) / 2)  # the round wall across the pads
        if bow > width:
            return no("rim-curved", width=width, bow=bow, fingers=f"{f1}/{f2}")
    blocker = hand_blocker(t, member, palm, f1)
    if blocker is not None:
        return no("hand-room", other=blocker, fingers=f"{f1}/{f2}")
    room = finger_room(t, member, palm, f1)
    for short, body, overlap in zip(room.shortfall, room.on_body, room.overlap, strict=True):
        if short <= TOUCH:
            continue
        lands = body or calibrated  # calibrated: on a sibling too (a lug below the rim)
        if not (lands and short <= RIM_STOP_TOLERANCE and overlap >= MIN_PAD_OVERLAP):
            values = {"shortfall": short, "tolerance": RIM_STOP_TOLERANCE, "pad_overlap": overlap}
            return no("rim-finger-room", fingers=f"{f1}/{f2}", **values)
    thin = width < MIN_PINCH
    carries = EXTENDED_LIFT_LIMIT if calibrated and not thin else RIM_LIFT_LIMIT
    if t.mass > carries:
        return no("rim-payload", mass=t.mass, limit=carries)
    gx, gy = m.box.center_xy
    bx, by = centre_of_mass(t)
    lever = math.hypot(gx - bx, gy - by)
    moment = t.mass * G * lever
    full_pad = calibrated and m.box.size[2] >= FULL_PAD_RIM - 1e-9
    thin_limit = CALIBRATED_THIN_TORQUE_LIMIT if calibrated else THIN_TORQUE_LIMIT
    # calibrated, a rim taking the whole pad: the thicker it is, the more it bears
    limit = thin_limit if thin else rim_couple_limit(width) if full_pad else TORQUE_LIMIT
    if moment > limit:
        return no("torque", mass=t.mass, lever=lever, moment=moment, limit=limit)
    return None


def wall_bow(radius: float) -> float:
    """m a round wall of `radius` m bows across the flat pads' width (`hand.PAD_WIDTH`): a
    wall thinner than that bow is not straddled by pads facing each other through it (the
    inner pad touches it at its two ends, the outer at its middle) and the calibrated rules
    refuse a sub-millimetre wall so bowed (a 7.7 cm tumbler of 0.8 mm slipped out, pots of
    14-19 cm held; 0.9 mm walls bowed 1.0 mm are the edge: they slipped out on one machine
    and held on another, so the rule errs on the side of refusing them)."""
    return (PAD_WIDTH / 2) ** 2 / (2 * radius)


def rim_couple_limit(width: float) -> float:
    """N m a rim `width` m thick, taking the whole pad, bears in the calibrated rules:
    `RIM_COUPLE_BASE` and the pads' friction couple across its thickness."""
    return RIM_COUPLE_BASE + GRIP_FORCE * EDGE_COUPLE_SHARE * PAD_FRICTION * width


def rim_pinches(t: ObjectType, calibrated: bool = True) -> list[tuple[str, str, str, str]]:
    """(member, palm, finger1, finger2) rim pinches that lift `t` (`rim_pinch_refusal`)."""
    out = []
    for name, m in t.members.items():
        if m.kind not in ("edge", "body"):
            continue
        for f1, f2 in (("left", "right"), ("front", "back")):
            if rim_pinch_refusal(t, name, "on", f1, f2, False, calibrated) is None:
                out.append((name, "on", f1, f2))
    return out


__all__ = [
    "CALIBRATED_MIN_WIDTH",
    "CALIBRATED_THIN_TORQUE_LIMIT",
    "RIM_COUPLE_BASE",
    "RIM_LIFT_LIMIT",
    "RIM_MIN_WIDTH",
    "RIM_STOP_TOLERANCE",
    "rim_couple_limit",
    "rim_pinch_refusal",
    "rim_pinches",
    "wall_bow",
]
