"""The room an object leaves for the Panda's fingers, and what a grasp can hold: geometry only.

The rule parser grants a grasp only where the hand can carry it out. Everything here is
computed from a type's attributes (member boxes, part shapes, sizes and heights, mass) and
from facts about the robot: the Franka Hand's fingers and the way a grasp is decoded
(`utamp_gym.sim.decode`: the TCP at the member's middle, `GRASP_DEPTH` below its palm face,
fingertips `TIP_BELOW_TCP` below the TCP and at least `TIP_CLEARANCE` above the object's
bottom). Nothing here knows an object, a type or a family by name. The material the fingers
meet, and what stands, are `utamp_gym.affordances.solids`.

**Finger room** (`finger_room`): each finger descends beside its side of the member, opened
`OPEN_CLEARANCE` beyond it (less if the hand's 8 cm do not allow it), then closes. It is a pad
(the lowest `PAD_HEIGHT`, `PAD_THICKNESS` across, `PAD_WIDTH` wide) under a thicker upper
finger. The finger stops where it first meets material beside the member; the shortfall is
how far above its target that is. A member with its own geometry (a handle, a neck, a lid, a
body) needs no shortfall at all: the motion planner allows fingers to touch only the grasped
member. An edge that is the body's own wall (a tray's rim, a bowl's rim, a plate's rim) may
let a finger land up to `STOP_TOLERANCE` early on the body (the approach guard stops the hand
1 cm short at most), as long as the pad still overlaps the edge by `MIN_PAD_OVERLAP`: a
handleless board lying flat has no room beside its edges, the fingers would meet the board
or the table.

**What a grasp holds** (`holds`): the object's weight hangs at a lever from the grasp point
(the member's middle to the body's centre, horizontally); its moment turns the object between
the pads unless the pads' friction holds it, up to `TORQUE_LIMIT`, and only `TORQUE_LIMIT_ABOVE`
when the object's centre lies above the grasp (an upside-down pot held by a lug near its
rim tips over in the grasp). The extended domain (``utamp2x``) allows a wrapped member (a
handle) holding the object hanging up to `EXTENDED_TORQUE_LIMIT`, as measured in physics.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from utamp_gym.affordances.solids import member_box, realised_by_body, solids
from utamp_gym.affordances.why import REFUSED, Refusal
from utamp_gym.scene.catalogue import Member, ObjectType
from utamp_gym.scene.geometry import NORMALS, axis_of
from utamp_gym.scene.shapes import BAR, loop_axis

# ------------------------------------------------------------------ the Franka Hand
GRIPPER_OPENING = 0.08  # m, fully open
WRAP_CLEARANCE = 0.003  # m a side: the open fingers must clear what they close on
PAD_WIDTH = 0.0176  # m, across the finger (the rubber tip)
PAD_THICKNESS = 0.0152  # m, along the closing direction
PAD_HEIGHT = 0.0184  # m
LOWER_FINGER = 0.033  # m above the tip: the pad and the slim part of the finger
UPPER_FINGER = (0.021, 0.026, 0.022)  # m: height, thickness, width of the finger above
NOISE_MARGIN = 0.002  # m, the robot's pose estimate is this uncertain (one sigma)
HAND_ABOVE_TCP = 0.031  # m: the hand's underside above the TCP
HAND_HALF_THICKNESS = 0.0172  # m: half the hand's thickness across the fingers' plane, low down
#: the wrist (the Panda's link 7, measured on its collision mesh in the TCP frame): its
#: underside this far above the TCP, this half width across the fingers' plane, and reaching
#: this far along the fingers' axis on its longer (joint-housing) side
WRIST_ABOVE_TCP, WRIST_HALF_WIDTH, WRIST_REACH = 0.1036, 0.0439, 0.088
MIN_PINCH = 0.007  # m: a pinched wall the 70 N squeeze leaves wider than the 4 mm the hand
#: reads as "holding something"
# ------------------------------------------------------------------ how a grasp is decoded
GRASP_DEPTH = 0.025  # m below the member's palm face (at most half the member)
TIP_BELOW_TCP = 0.0095  # m
TIP_CLEARANCE = 0.003  # m above the object's bottom
OPEN_CLEARANCE = 0.008  # m a side beyond the member when the fingers come down
# ------------------------------------------------------------------ tolerances
STOP_TOLERANCE = 0.002  # m a finger may land early on the body it pinches
MIN_PAD_OVERLAP = 0.005  # m of pad on the pinched edge
TOUCH = 0.0005  # m: closer than this is touching, not colliding
CONTACT = 0.002  # m beside the face where the pad ends up touching (a curved wall bulges in)
# ------------------------------------------------------------------ what a grasp holds
G = 9.81
TORQUE_LIMIT = 1.4  # N m about the grasp, hanging (the object's centre below or level)
TORQUE_LIMIT_ABOVE = 0.8  # N m when the object's centre lies above the grasp
#: N m about a wrapped member (a handle) with the object hanging, in the extended domain,
#: as long as the part of it about the axis across the closing one stays within
#: `TORQUE_LIMIT`: the v1 handle grasps the paper's limit refuses whose lever runs across
#: the fingers' closing axis (1.41-2.53 N m: boards, saucepans, frying pans, stock pots in
#: the payload) were lifted and placed in physics; trays held at an end handle with the
#: fingers closing along the lever slipped at 2.36-2.47 N m
EXTENDED_TORQUE_LIMIT = 2.4
ABOVE = 0.005  # m: a centre this much above the grasp point counts as above
#: m above its target the hand may come to rest on the rim of an open body whose wall a
#: finger goes down inside (`fingers_refusal`'s `rest`, the extended domain's): the guarded
#: approach accepts a hand held up to 10 mm short (`utamp_gym.sim.grasp_phases.APPROACH_STOP`),
#: and in MuJoCo the hand stops 4-5 mm less short than its box here says (v1 mugs taken
#: by the handle across the wall: every one up to 15.4 mm lifted, from 15.6 mm none)
HAND_REST_TOLERANCE = 0.013


class FingerRoom(NamedTuple):
    """How far above its target each finger would stop (m), and the pad's overlap with the
    member when it stops there."""

    shortfall: tuple[float, float]
    on_body: tuple[bool, bool]  # the stop is on the grasped edge's own body
    overlap: tuple[float, float]
    stopped_by: tuple[str | None, str | None] = (None, None)  # the member it stops on


def grip_centre(t: ObjectType, member: str, lat: int, flipped: bool) -> float:
    """Where along the lateral axis `lat` the fingers close: the member's middle, or a loop
    handle's outer bar (`utamp_gym.scene.shapes`), as the decoder places them."""
    box = member_box(t, member, flipped)
    loop = loop_axis(t, t.members[member])
    if loop is None or loop[0] != lat:
        return (box.min[lat] + box.max[lat]) / 2
    sign = -loop[1] if flipped and lat == 1 else loop[1]
    outer = box.max[lat] if sign > 0 else box.min[lat]
    return outer - sign * BAR / 2


def tip_height(t: ObjectType, member: str, palm: str) -> float:
    """Where the decoder puts the fingertips (frame of the object turned palm-part up)."""
    box = member_box(t, member, palm == "under")
    bottom = min(member_box(t, m, palm == "under").min[2] for m in t.members)
    top = box.max[2]
    tcp = top - min(GRASP_DEPTH, (box.max[2] - box.min[2]) / 2)
    tcp = max(tcp, bottom + TIP_CLEARANCE + TIP_BELOW_TCP)
    return tcp - TIP_BELOW_TCP


def finger_room(t: ObjectType, member: str, palm: str, finger: str) -> FingerRoom:
    """Where the fingers closing along `finger`'s axis on `member` (palm on `palm`) stop."""
    flipped = palm == "under"
    box = member_box(t, member, flipped)
    ax = axis_of(finger)
    lat = 1 - ax
    width = box.max[ax] - box.min[ax]
    opening = min(OPEN_CLEARANCE, max(GRIPPER_OPENING - width, 0.0) / 2)
    tip = tip_height(t, member, palm)
    centre = grip_centre(t, member, lat, flipped)
    m = t.members[member]
    own = t.body.name if realised_by_body(t, m) else member
    material = [(n, s) for n, s in solids(t, flipped) if n != member]
    segments = (  # (height above the tip, from, to along the closing axis, half width)
        (0.0, CONTACT, opening + PAD_THICKNESS + NOISE_MARGIN, PAD_WIDTH / 2 + NOISE_MARGIN),
        (LOWER_FINGER, opening, opening + UPPER_FINGER[1] + NOISE_MARGIN,
         UPPER_FINGER[2] / 2 + NOISE_MARGIN),
    )  # fmt: skip
    shortfall, on_body, overlap, stopped_by = [], [], [], []
    for sign in (-1, 1):
        face = box.max[ax] if sign > 0 else box.min[ax]
        stop, stop_body, stopper = tip, True, None
        for above, near, far, half in segments:
            closing = sorted((face + sign * near, face + sign * far))
            rect = [(0.0, 0.0), (0.0, 0.0)]
            rect[ax] = (closing[0], closing[1])
            rect[lat] = (centre - half, centre + half)
            for name, s in material:
                if s.hi[2] - above > stop + 1e-12 and s.overlaps(rect[0], rect[1]):
                    stop, stop_body, stopper = s.hi[2] - above, name == own, name
        short = max(0.0, stop - tip)
        shortfall.append(short)
        on_body.append(stop_body)
        stopped_by.append(stopper)
        pad_lo = tip + short
        overlap.append(min(pad_lo + PAD_HEIGHT, box.max[2]) - max(pad_lo, box.min[2]))
    return FingerRoom(
        (shortfall[0], shortfall[1]),
        (on_body[0], on_body[1]),
        (overlap[0], overlap[1]),
        (stopped_by[0], stopped_by[1]),
    )


def finger_side(finger: str, sign: int, flipped: bool) -> str:
    """The side of the upright object that the finger closing from `sign` along `finger`'s
    axis lies on, the object turned palm part up (`flipped`: a half turn about x)."""
    ax = axis_of(finger)
    if flipped and ax == 1:
        sign = -sign
    return next(s for s, n in NORMALS.items() if n[ax] == sign)


def _opposite_side(side: str) -> str:
    normal = tuple(-v for v in NORMALS[side])
    return next(s for s, n in NORMALS.items() if n == normal)


def hand_room(t: ObjectType, member: str, palm: str, finger: str) -> bool:
    """The hand above the fingers comes down without landing on the object: no material
    (but the grasped member) rises above the hand's underside within its thickness across
    the fingers' plane (an upside-down pot whose lug stands out too little)."""
    return hand_blocker(t, member, palm, finger) is None


def hand_blocker(t: ObjectType, member: str, palm: str, finger: str) -> str | None:
    """The member the hand would land on (`hand_room`), or None."""
    landing = hand_landing(t, member, palm, finger)
    return landing[0] if landing else None


def hand_landing(t: ObjectType, member: str, palm: str, finger: str) -> tuple[str, float] | None:
    """(member, m above its target the hand would rest on it) for the highest material the
    hand above the fingers meets coming down (`hand_room`), or None: it meets nothing."""
    flipped = palm == "under"
    box = member_box(t, member, flipped)
    ax = axis_of(finger)
    lat = 1 - ax
    tcp = tip_height(t, member, palm) + TIP_BELOW_TCP
    bottom = tcp + HAND_ABOVE_TCP + STOP_TOLERANCE
    reach = (box.max[ax] - box.min[ax]) / 2 + OPEN_CLEARANCE + UPPER_FINGER[1]
    cl, ca = grip_centre(t, member, lat, flipped), (box.min[ax] + box.max[ax]) / 2
    material = [(n, s) for n, s in solids(t, flipped) if n != member and s.hi[2] > bottom]
    rect = [(0.0, 0.0), (0.0, 0.0)]
    rect[ax] = (ca - reach, ca + reach)
    rect[lat] = (cl - HAND_HALF_THICKNESS, cl + HAND_HALF_THICKNESS)
    met = [(n, s.hi[2]) for n, s in material if s.overlaps(rect[0], rect[1])]
    if not met:
        return None
    name = met[0][0]
    return name, max(h for _, h in met) - (tcp + HAND_ABOVE_TCP)


def wrist_blocker(t: ObjectType, member: str, palm: str, finger: str) -> str | None:
    """The member the wrist above the hand would land on, or None: an upside-down stock pot
    held by a lug near the table, its floor standing higher than the wrist comes down
    (procedural-v2/test-tasks/0005: the wrist met the floor, the hand stopped 11 mm short)."""
    flipped = palm == "under"
    box = member_box(t, member, flipped)
    ax = axis_of(finger)
    lat = 1 - ax
    tcp = tip_height(t, member, palm) + TIP_BELOW_TCP
    bottom = tcp + WRIST_ABOVE_TCP + STOP_TOLERANCE
    cl, ca = grip_centre(t, member, lat, flipped), (box.min[ax] + box.max[ax]) / 2
    half = WRIST_HALF_WIDTH + NOISE_MARGIN
    rect = [(0.0, 0.0), (0.0, 0.0)]
    rect[ax] = (ca - WRIST_REACH - NOISE_MARGIN, ca + WRIST_REACH + NOISE_MARGIN)
    rect[lat] = (cl - half, cl + half)
    material = [(n, s) for n, s in solids(t, flipped) if n != member and s.hi[2] > bottom]
    return next((n for n, s in material if s.overlaps(rect[0], rect[1])), None)


def fingers_fit(t: ObjectType, member: str, palm: str, finger: str) -> bool:
    """Both fingers reach their places beside the member, the hand comes down above them,
    and a pinched edge is thick enough to be felt (see the module docstring)."""
    return fingers_refusal(t, member, palm, finger, why=False) is None


def fingers_refusal(
    t: ObjectType, member: str, palm: str, finger: str, why: bool = True, rest: str | None = None
) -> Refusal | None:
    """Why `fingers_fit` refuses (None: the fingers fit; `REFUSED` if not `why`). `rest`
    (the extended domain's): a member the hand may come to rest on, up to
    `HAND_REST_TOLERANCE` above its target, the pads still on the grasped member."""
    m = t.members[member]
    fingers = f"{finger}/{_opposite_side(finger)}" if why else ""
    width = m.box.size[axis_of(finger)]
    if m.kind == "edge" and width < MIN_PINCH - 1e-9:
        values = {"member": member, "width": width, "fingers": fingers, "limit": MIN_PINCH}
        return Refusal("pinch", values) if why else REFUSED
    landing = hand_landing(t, member, palm, finger)
    if landing is not None and not _rests(t, member, palm, landing, rest):
        values = {"member": member, "other": landing[0], "fingers": fingers}
        if rest is not None and landing[0] == rest:
            values.update(shortfall=landing[1], tolerance=HAND_REST_TOLERANCE)
        return Refusal("hand-room", values) if why else REFUSED
    room = finger_room(t, member, palm, finger)
    edge = realised_by_body(t, m)
    for i, (short, body, overlap) in enumerate(
        zip(room.shortfall, room.on_body, room.overlap, strict=True)
    ):
        if short <= TOUCH:
            continue
        if not (edge and body and short <= STOP_TOLERANCE and overlap >= MIN_PAD_OVERLAP):
            if not why:
                return REFUSED
            values = {
                "member": member,
                "fingers": fingers,
                "side": finger_side(finger, (-1, 1)[i], palm == "under"),
                "shortfall": short,
                "other": room.stopped_by[i],
                "tolerance": STOP_TOLERANCE if edge else 0.0,
                "pad_overlap": overlap,
            }
            return Refusal("finger-room", values)
    return None


def _rests(
    t: ObjectType, member: str, palm: str, landing: tuple[str, float], rest: str | None
) -> bool:
    """The hand may rest where it lands (`fingers_refusal`'s `rest`): on `rest`, at most
    `HAND_REST_TOLERANCE` above its target, the pads keeping `MIN_PAD_OVERLAP` on the member."""
    other, short = landing
    if rest is None or other != rest or short > HAND_REST_TOLERANCE:
        return False
    top = member_box(t, member, palm == "under").max[2]
    return top - (tip_height(t, member, palm) + short) >= MIN_PAD_OVERLAP


def width_fits(width: float, member: Member) -> bool:
    """The open hand clears a member it wraps (a body, a handle); an edge is pinched."""
    return width <= grip_limit(member)


def grip_limit(member: Member) -> float:
    """The widest `member` the hand closes on: the opening, less `WRAP_CLEARANCE` a side for
    a member it wraps."""
    return GRIPPER_OPENING - (0.0 if member.kind == "edge" else 2 * WRAP_CLEARANCE)


def holds(
    t: ObjectType, member: str, palm: str, extended: bool = False, finger: str | None = None
) -> bool:
    """The pads hold the moment of the object's weight about the grasp (module docstring)."""
    return hold_refusal(t, member, palm, why=False, extended=extended, finger=finger) is None


def hold_refusal(
    t: ObjectType,
    member: str,
    palm: str,
    why: bool = True,
    extended: bool = False,
    finger: str | None = None,
) -> Refusal | None:
    """Why `holds` refuses (None: the pads hold it; `REFUSED` if not `why`). `extended` (the
    extended domain's rules) with the fingers closing along `finger`'s axis: a wrapped
    member holding the object hanging is allowed `EXTENDED_TORQUE_LIMIT`, the part of the
    moment about the axis across the closing one `TORQUE_LIMIT`."""
    flipped = palm == "under"
    grip = member_box(t, member, flipped)
    body = member_box(t, t.body.name, flipped)
    gx, gy = grip.center_xy
    bx, by = body.center_xy
    lever = math.hypot(gx - bx, gy - by)
    grasp_z = grip.max[2] - min(GRASP_DEPTH, (grip.max[2] - grip.min[2]) / 2)
    above = (body.min[2] + body.max[2]) / 2 > grasp_z + ABOVE
    limit = TORQUE_LIMIT_ABOVE if above else TORQUE_LIMIT
    if extended and finger is not None and not above and t.members[member].kind != "edge":
        along = abs((gx - bx, gy - by)[axis_of(finger)])  # the lever along the closing axis
        if t.mass * G * along <= TORQUE_LIMIT:
            limit = EXTENDED_TORQUE_LIMIT
    moment = t.mass * G * lever
    if moment <= limit:
        return None
    if not why:
        return REFUSED
    values = {"member": member, "mass": t.mass, "lever": lever, "moment": moment}
    return Refusal("torque", {**values, "limit": limit, "centre_above": above})


__all__ = [
    "GRIPPER_OPENING",
    "HAND_REST_TOLERANCE",
    "FingerRoom",
    "finger_room",
    "finger_side",
    "fingers_fit",
    "fingers_refusal",
    "grip_centre",
    "grip_limit",
    "hand_blocker",
    "hand_landing",
    "hand_room",
    "hold_refusal",
    "holds",
    "tip_height",
    "width_fits",
    "wrist_blocker",
]
