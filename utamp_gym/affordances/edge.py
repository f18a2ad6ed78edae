"""Edge pinches: a flat board slid until it overhangs the table's near edge, pinched there
(the extended domain ``utamp2x``'s ``slide-edge``, `utamp_gym.sim.edge` in physics).

A slab too wide for the open hand and too flat to pinch from above is pressed from above,
dragged to the table's near edge until its back end overhangs by `OVERHANG`, and
pinched across its thickness there, the hand horizontal. The rules decide from geometry and
mass alone, never from a family or a type name:

* a slab: its top is its highest face where the fingertips press (no usable surface below
  the top, no member above it), it stands on its whole underside (a flat ``under`` as large
  as its body: a plate's foot or a pan's flared wall leaves its back end hollow), and its
  thickness (the closing direction) lies within `MIN_THICKNESS` .. `MAX_THICKNESS` (the
  8 cm opening less the clearance a side);
* its back end (``back``, the side facing the near edge at the scene's yaw) is solid where the
  pads close: the member reaching it spans the whole thickness, is at least `hand.PAD_WIDTH`
  wide and `PAD_DEPTH` deep;
* its centre of mass stays on the table, `COM_MARGIN` inside the edge, while it overhangs;
* dragging it: the pads' friction (`PAD_FRICTION`) under `PRESS_FORCE` beats the table's
  (`TABLE_FRICTION`) under its weight and the press;
* it fits the drag line: its half-width leaves `BASE_CLEARANCE` to the base's axis at the
  farthest line `EDGE_Y`;
* lifting it: at most `EDGE_LIFT_LIMIT`, and the moment of its weight about the pinch within
  what the pads' friction couple across its thickness bears (`edge_torque_limit`); a board
  it turns out of is slid further out and pinched deeper, nearer its centre of mass
  (`edge_depth`), where its end is solid that deep and its centre of mass stays on the table.

The facts: ``canEdgePinch`` (the grasp body/back/on/under, lifting included) and
``canSlideEdge`` from each fixed flat top it rests on (`edge_slide_facts`). What the skill
meets in a scene (another object on the drag line) the skill reports.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from utamp_gym.affordances.calibrated import EXTENDED_LIFT_LIMIT
from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.hand import (
    GRIPPER_OPENING,
    OPEN_CLEARANCE,
    PAD_HEIGHT,
    PAD_WIDTH,
    G,
)
from utamp_gym.affordances.solids import centre_of_mass
from utamp_gym.affordances.why import REFUSED, Refusal
from utamp_gym.scene.catalogue import Member, ObjectType

# the geometry the skill (`utamp_gym.sim.edge`) works to
#: m the board's back end is dragged beyond the near edge: the pads (`PAD_IN` inside the end,
#: 18.5 mm long) and the lower finger then clear the table's edge by 5 mm
OVERHANG = 0.035
PAD_IN = 0.022  # m: the pads' middle this far inside the board's back end
#: m: the deeper pinch (`edge_depth`) a board whose weight turns out of a `PAD_IN` one is
#: taken by, slid `DEEP_PAD_IN - PAD_IN` further out: its pads then close nearer its centre
#: of mass, the fingertips still short of the hand's reach over the board (paddle boards
#: of 1.1-1.5 kg were lifted and placed so, their moment about a `PAD_IN` pinch beyond
#: what it bears)
DEEP_PAD_IN = 0.037
#: m from the base's axis (absolute y) the board is dragged to, in turn: the pinch beyond
#: the near edge is reached there (0.4 m is not) and the board clears the robot's base
EDGE_Y = (0.3, 0.33, 0.27)
BASE_CLEARANCE = 0.16  # m from the base's axis the board's near side keeps while dragged
#: the grasp of an edge pinch: member, palm, fingers (the hand horizontal, closing vertically)
EDGE_GRASP = ("body", "back", "on", "under")
MIN_THICKNESS = 0.005  # m
MAX_THICKNESS = GRIPPER_OPENING - 2 * OPEN_CLEARANCE  # m
PAD_DEPTH = PAD_IN + 0.0095  # m of material behind the back end the pads close on
COM_MARGIN = 0.02  # m the centre of mass stays inside the table's edge
PAD_FRICTION, TABLE_FRICTION = 1.5, 0.5  # the simulator's finger pads, table and objects
PRESS_FORCE = 40.0  # N the pressing fingertips bear down with at least (60-130 N measured)
EDGE_LIFT_LIMIT = EXTENDED_LIFT_LIMIT  # kg
GRIP_FORCE = 70.0  # N each pad squeezes with (`utamp_gym.robot.panda_mjcf.GRIPPER_FORCE`)
#: the pads on the board's top and bottom resist its turning (`edge_torque_limit`) by their
#: squeeze shifting to their ends (`GRIP_FORCE` x half the pad's length along the board) and by
#: the couple of their friction across its thickness, of which this share holds: calibrated
#: on every board of procedural v1 slid to the edge (`benchmarks/edge_slide.py`)
EDGE_COUPLE_SHARE = 0.65
#: the share that holds for a `DEEP_PAD_IN` pinch: more of the board's end lies behind the
#: pads, against the fingers, as it turns (v1 boards pinched deep: lifted with shares up to
#: 0.78 needed; a 1.4 kg paddle board needing 0.99 slipped)
DEEP_COUPLE_SHARE = 0.8


def _no(rule: str, why: bool, **values: object) -> Refusal:
    return Refusal(rule, values) if why else REFUSED


def edge_pinch_refusal(t: ObjectType, why: bool = True) -> Refusal | None:
    """Why `t` cannot be slid to the table's edge and lifted by an edge pinch (None: it can;
    see the module docstring)."""
    if not t.movable:
        return _no("fixed", why, type=t.name)
    box, body = t.bbox, t.body.box
    on, under = t.parts["on"], t.parts["under"]
    top = float(box.max[2])
    pressed = on.shape == "flat" and (on.height is None or on.height >= top - 1e-6)
    if not pressed or body.max[2] < top - 1e-6:
        return _no("edge-slab", why, what="its top is no flat face at its highest")
    if under.shape != "flat" or under.size is None:
        return _no("edge-slab", why, what=f"it does not stand on a flat underside ({under.shape})")
    if any(under.size[i] < body.size[i] - 1e-6 for i in (0, 1)):
        return _no("edge-slab", why, what="it stands on a foot smaller than its body")
    thick = float(box.size[2])
    if not MIN_THICKNESS <= thick <= MAX_THICKNESS:
        return _no("edge-thickness", why, thickness=thick, limits=(MIN_THICKNESS, MAX_THICKNESS))
    x0 = float(box.min[0])
    end = [m for m in t.members.values() if m.box.min[0] <= x0 + 1e-6]
    solid = _solid_end(t, PAD_IN)
    if not solid:
        return _no("edge-end", why, member=end[0].name if end else "nothing", depth=PAD_DEPTH)
    inside = centre_of_mass(t)[0] - x0 - OVERHANG
    if inside < COM_MARGIN:
        return _no("edge-com", why, inside=inside, margin=COM_MARGIN)
    drag = (PAD_FRICTION - TABLE_FRICTION) * PRESS_FORCE / (TABLE_FRICTION * G)
    if t.mass > drag:
        return _no("edge-drag", why, mass=t.mass, limit=drag)
    half = float(box.size[1]) / 2
    if max(EDGE_Y) - half < BASE_CLEARANCE - 1e-9:
        return _no("edge-wide", why, half=half, line=max(EDGE_Y), clearance=BASE_CLEARANCE)
    if t.mass > EDGE_LIFT_LIMIT:
        return _no("payload", why, member="body", mass=t.mass, limit=EDGE_LIFT_LIMIT,
                   kind="edge pinch", payload=3.0)  # fmt: skip
    depth = edge_depth(t)
    lever = _lever(t, depth)
    moment = t.mass * G * lever
    limit = edge_torque_limit(thick, DEEP_COUPLE_SHARE if depth > PAD_IN else EDGE_COUPLE_SHARE)
    if moment > limit:
        return _no("torque", why, member=_solid_end(t, depth)[0].name, mass=t.mass,
                   lever=lever, moment=moment, limit=limit)  # fmt: skip
    return None


def _solid_end(t: ObjectType, depth: float) -> list[Member]:
    """The members at `t`'s back end the pads close on `depth` inside it: spanning the
    whole thickness, `hand.PAD_WIDTH` wide and the pads' reach deep."""
    box = t.bbox
    x0, top = float(box.min[0]), float(box.max[2])
    return [
        m
        for m in t.members.values()
        if m.box.min[0] <= x0 + 1e-6
        and m.box.min[2] <= box.min[2] + 1e-6
        and m.box.max[2] >= top - 1e-6
        and m.box.size[1] >= PAD_WIDTH - 1e-9
        and m.box.size[0] >= depth + PAD_DEPTH - PAD_IN - 1e-9
    ]


def _lever(t: ObjectType, depth: float) -> float:
    """m from a pinch `depth` inside `t`'s back end to its centre of mass, horizontally."""
    cx, cy = centre_of_mass(t)
    solid = _solid_end(t, depth) or _solid_end(t, PAD_IN)
    pinch_y = float(solid[0].box.center_xy[1]) if solid else cy
    return math.hypot(cx - (float(t.bbox.min[0]) + depth), cy - pinch_y)


def edge_depth(t: ObjectType) -> float:
    """m inside `t`'s back end the pads close (the skill, `utamp_gym.sim.edge`, and the
    rule agree on it): `PAD_IN`, or `DEEP_PAD_IN` where the weight's moment about a
    `PAD_IN` pinch exceeds what it bears (`edge_torque_limit`), the end is solid that deep
    and the centre of mass stays `COM_MARGIN` on the table with the longer overhang."""
    thick = float(t.bbox.size[2])
    if t.mass * G * _lever(t, PAD_IN) <= edge_torque_limit(thick):
        return PAD_IN
    x0 = float(t.bbox.min[0])
    inside = centre_of_mass(t)[0] - x0 - edge_overhang(DEEP_PAD_IN)
    if not _solid_end(t, DEEP_PAD_IN) or inside < COM_MARGIN:
        return PAD_IN
    return DEEP_PAD_IN


def edge_overhang(depth: float) -> float:
    """m the board's back end overhangs the table's edge for a pinch `depth` inside it."""
    return OVERHANG + depth - PAD_IN


def edge_torque_limit(thickness: float, share: float = EDGE_COUPLE_SHARE) -> float:
    """N m about an edge pinch a board `thickness` m thick bears: ``F (L / 2 + s mu h)``, F
    the squeeze, L the pads' length, mu their friction, s `share` (`EDGE_COUPLE_SHARE`, or
    `DEEP_COUPLE_SHARE` for a deep pinch)."""
    return GRIP_FORCE * (PAD_HEIGHT / 2 + share * PAD_FRICTION * thickness)


def edge_facts(t: ObjectType) -> set[Fact]:
    """``canEdgePinch`` of `t` if an edge pinch lifts it (the fact grants the lift too: no
    ``canLift``, which would let a pick from above lift it by the body)."""
    if edge_pinch_refusal(t, False) is not None:
        return set()
    return {("canEdgePinch", t.name, *EDGE_GRASP)}


def edge_slide_facts(types: Iterable[ObjectType], facts: Iterable[Fact]) -> set[Fact]:
    """``canSlideEdge`` (object, fixed support, parts): an object with ``canEdgePinch``
    resting on its flat ``under`` on a fixed flat top (``isP2PSupportive`` in `facts`)."""
    facts = set(facts)
    types = list(types)
    out: set[Fact] = set()
    for t1 in types:
        if not any(f[0] == "canEdgePinch" and f[1] == t1.name for f in facts):
            continue
        for t2 in types:
            if t2.movable or t2.parts["on"].shape != "flat":
                continue
            if ("isP2PSupportive", "on", t2.name, "under", t1.name) in facts:
                out.add(("canSlideEdge", t1.name, t2.name, "under", "on"))
    return out


__all__ = [
    "BASE_CLEARANCE",
    "DEEP_COUPLE_SHARE",
    "DEEP_PAD_IN",
    "EDGE_COUPLE_SHARE",
    "EDGE_GRASP",
    "EDGE_Y",
    "OVERHANG",
    "PAD_IN",
    "edge_depth",
    "edge_facts",
    "edge_overhang",
    "edge_pinch_refusal",
    "edge_slide_facts",
    "edge_torque_limit",
]
