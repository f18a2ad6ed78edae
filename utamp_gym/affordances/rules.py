"""Rule-based parser: physical attributes -> inter-object affordances.

The rules are the paper's assumptions made explicit (Sections IV and VI):

* the support rules (what an object rests on, which parts carry others, whose footprint
  fits whose surface, the load a supporter bears): `utamp_gym.affordances.support`;
* the gripper approaches from above (palm on a part that can face up) and comes down
  onto the member's palm face: no sibling member (the body included) stands over it
  (a bottle's neck over its body, a bowl's floor under its rim when upside-down); its
  fingers close across a member that fits the 8 cm opening with room to spare (an edge
  is pinched) and find room beside it: no sibling member in the way, and no material of
  the object under a finger above its target (`utamp_gym.affordances.hand`: a slab's edge
  lying flat, a bowl's curved wall beside a rim strip, a jar's shoulder beside its lid);
* an object can be lifted by a member if it is well below the Panda's 3 kg payload
  (edge grasps carry much less) and the pads hold the moment of its weight about the
  grasp (a heavy board far out on its handle, an upside-down pot by a lug); an edge grasp
  is only useful when it can lift the object or when the object cannot be lifted at all
  (then it is slid);
* an object that cannot be lifted but rests flat on a fixed surface can be slid.

Each rule decides through its ``*_refusal`` twin (`rest_refusal`, `supportable_refusal`,
`supportive_refusal`, `p2p_refusal`, `grasp_refusal`, `lift_refusal`, `pick_refusal`): None
grants the affordance, a `utamp_gym.affordances.why.Refusal` names the failing test and its
numbers, so an explanation (`utamp plan --explain`) says exactly why a rule refuses. The
boolean rules ask with ``why=False`` (any refusal is then the shared `REFUSED`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from utamp_gym.affordances.calibrated import (
    EXTENDED_LIFT_LIMIT,
    low_cover,
    lug_wall,
    shoulder_rest,
)
from utamp_gym.affordances.edge import edge_facts, edge_slide_facts
from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.hand import (
    EXTENDED_TORQUE_LIMIT,
    WRAP_CLEARANCE,
    G,
    fingers_refusal,
    grip_limit,
    hold_refusal,
    holds,
    width_fits,
    wrist_blocker,
)
from utamp_gym.affordances.hand import GRIPPER_OPENING as GRIPPER_OPENING  # re-exported
from utamp_gym.affordances.rim import rim_pinches
from utamp_gym.affordances.support import (  # re-exported: the support rules
    LOAD_CAPACITY as LOAD_CAPACITY,
)
from utamp_gym.affordances.support import PLACE_MARGIN as PLACE_MARGIN
from utamp_gym.affordances.support import SPAN_MARGIN as SPAN_MARGIN
from utamp_gym.affordances.support import can_rest_on as can_rest_on
from utamp_gym.affordances.support import is_supportable as is_supportable
from utamp_gym.affordances.support import is_supportive as is_supportive
from utamp_gym.affordances.support import p2p_refusal as p2p_refusal
from utamp_gym.affordances.support import p2p_supportive, rest_refusal
from utamp_gym.affordances.support import supportable_refusal as supportable_refusal
from utamp_gym.affordances.support import supportive_refusal as supportive_refusal
from utamp_gym.affordances.why import REFUSED, Refusal
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import NORMALS, OPPOSITE, SIDES, axis_of

MIN_GRASP_WIDTH = 0.005  # m
PAYLOAD = 3.0  # kg, Franka Panda
LIFT_FRACTION = 0.5  # "significantly lighter than the payload"
EDGE_LIFT_LIMIT = 0.5  # kg an edge (pinch) grasp can carry
BLOCKING_GAP = 0.005  # m: a sibling member this close blocks a finger
FINGER_PAIRS = (("left", "right"), ("front", "back"))
PALM_PARTS = ("on", "under")
WRAPS = f"closes around with {WRAP_CLEARANCE * 100:.1f} cm to spare a side"


def _blocker(t: ObjectType, member: str, side: str) -> str | None:
    """A sibling member within `BLOCKING_GAP` of the member's `side` (a finger's place)."""
    box = t.members[member].box
    return next(
        (
            n
            for n, m in t.members.items()
            if n != member and box.touches_side(m.box, side, BLOCKING_GAP)
        ),
        None,
    )


def _cover(t: ObjectType, member: str, palm: str) -> str | None:
    """A sibling member that reaches beyond the member's `palm` face over that face (the
    hand coming down against the palm part would meet it first), or None."""
    box = t.members[member].box
    ax = axis_of(palm)
    for name, m in t.members.items():
        other = m.box
        if name == member:
            continue
        beyond = (
            other.max[ax] > box.max[ax] + 1e-9
            if NORMALS[palm][ax] > 0
            else other.min[ax] < box.min[ax] - 1e-9
        )
        over = all(
            box.min[i] < other.max[i] - 1e-9 and other.min[i] < box.max[i] - 1e-9
            for i in range(3)
            if i != ax
        )
        if beyond and over:
            return name
    return None


def _palm_refusal(
    t: ObjectType, member: str, palm: str, why: bool = True, extended: bool = False
) -> Refusal | None:
    """Why the hand cannot come down with its palm on `palm` onto `member` (None: it can;
    `extended`: around a low cover, `utamp_gym.affordances.calibrated.low_cover`)."""
    below = rest_refusal(t, OPPOSITE[palm], why)
    if below is not None:  # that part never faces up
        if not why:
            return REFUSED
        return Refusal("palm-never-up", {"member": member, "palm": palm, "why": below})
    other = _cover(t, member, palm)
    if other is not None and not (extended and low_cover(t, member, palm, other)):
        if not why:
            return REFUSED
        return Refusal("covered", {"member": member, "palm": palm, "other": other})
    return None


def _fingers_refusal(
    t: ObjectType,
    member: str,
    palm: str,
    f1: str,
    f2: str,
    why: bool = True,
    extended: bool = False,
) -> Refusal | None:
    """Why the fingers cannot close on `member` along f1/f2 (None: they can; `extended`: a
    finger may go down inside an open body beside a lug, `calibrated.lug_wall`)."""
    m = t.members[member]
    width = float(m.box.size[axis_of(f1)])
    if width < MIN_GRASP_WIDTH:
        if not why:
            return REFUSED
        values = {"member": member, "width": width, "fingers": f"{f1}/{f2}"}
        return Refusal("too-thin", {**values, "limit": MIN_GRASP_WIDTH})
    if not width_fits(width, m):
        if not why:
            return REFUSED
        how = "pinches" if m.kind == "edge" else WRAPS
        values = {"member": member, "width": width, "fingers": f"{f1}/{f2}"}
        values.update(limit=grip_limit(m), opening=GRIPPER_OPENING, how=how)
        return Refusal("grip-width", values)
    excused = set()  # what the extended domain's grasps let a finger or the hand pass
    rest = None  # what the hand may come to rest on (`hand.HAND_REST_TOLERANCE`)
    for side in (f1, f2):
        other = _blocker(t, member, side)
        if other is not None and extended and lug_wall(t, member, palm, side, other):
            excused.add(("finger-room", other))  # the pads close on the lug and the wall
            rest = other  # the hand above may rest on that wall's rim
            continue
        if other is not None:
            if not why:
                return REFUSED
            values = {"member": member, "side": side, "other": other, "gap": BLOCKING_GAP}
            return Refusal("finger-blocked", values)
    refusal = fingers_refusal(t, member, palm, f1, why or extended, rest)
    if extended and refusal is not None:
        other = refusal.values.get("other")
        if other is not None and low_cover(t, member, palm, other):
            excused.add(("hand-room", other))  # the hand comes down around the cover
        if other == t.body.name and shoulder_rest(t, member, palm, f1):
            excused.add(("finger-room", other))  # the fingers land on a cap's shoulder
        if (refusal.rule, other) in excused:
            refusal = None
    if extended and refusal is None:  # the wrist above the hand (the paper's rules: the hand)
        wrist = wrist_blocker(t, member, palm, f1)
        if wrist is not None:
            values = {"member": member, "other": wrist, "fingers": f"{f1}/{f2}"}
            return Refusal("wrist-room", values) if why else REFUSED
    return refusal if why or refusal is None else REFUSED


def grasp_refusal(t: ObjectType, member: str, palm: str, f1: str, f2: str) -> Refusal | None:
    """Why the gripper cannot close on `member` with its palm on `palm` and its fingers on
    f1/f2 (None: `geometric_grasps` has it)."""
    if not t.movable:
        return Refusal("fixed", {"type": t.name})
    return _palm_refusal(t, member, palm) or _fingers_refusal(t, member, palm, f1, f2)


def geometric_grasps(t: ObjectType, extended: bool = False) -> list[tuple[str, str, str, str]]:
    """(member, palm, finger1, finger2) grasps the gripper can physically close on
    (`extended`: with the extended domain's, `utamp_gym.affordances.calibrated`)."""
    if not t.movable:
        return []
    out = []
    for mname in t.members:
        for palm in PALM_PARTS:
            if _palm_refusal(t, mname, palm, False, extended) is not None:
                continue
            for f1, f2 in FINGER_PAIRS:
                if _fingers_refusal(t, mname, palm, f1, f2, False, extended) is None:
                    out.append((mname, palm, f1, f2))
    return out


def liftable_via(t: ObjectType, member: str, extended: bool = False) -> bool:
    return lift_refusal(t, member, False, extended) is None


def lift_refusal(
    t: ObjectType, member: str, why: bool = True, extended: bool = False
) -> Refusal | None:
    """Why `t` is too heavy to lift by `member` (None: light enough; `extended`: a wrapped
    member carries `calibrated.EXTENDED_LIFT_LIMIT`)."""
    edge = t.members[member].kind == "edge"
    wrap = EXTENDED_LIFT_LIMIT if extended else PAYLOAD * LIFT_FRACTION
    limit = EDGE_LIFT_LIMIT if edge else wrap
    if t.mass <= limit:
        return None
    if not why:
        return REFUSED
    kind = "pinch (edge)" if edge else "wrapping"
    values = {"member": member, "mass": t.mass, "limit": limit, "kind": kind}
    return Refusal("payload", {**values, "payload": PAYLOAD})


def pick_refusal(
    t: ObjectType, member: str, palm: str, f1: str, f2: str, extended: bool = False
) -> Refusal | None:
    """Why `object_facts` grants no ``canGraspFrom`` with ``canLift`` for this grasp: the
    gripper cannot close on it, the object is too heavy, or it turns out of the pads.
    `extended`: by the extended domain's grasp rules (`object_facts` with `extended`, the
    calibrated ones); a rim pinch of the member is asked separately (`rim_pinch_refusal`)."""
    if not extended:
        return (
            grasp_refusal(t, member, palm, f1, f2)
            or lift_refusal(t, member)
            or hold_refusal(t, member, palm)
        )
    if not t.movable:
        return Refusal("fixed", {"type": t.name})
    refusal = (
        _palm_refusal(t, member, palm, True, True)
        or _fingers_refusal(t, member, palm, f1, f2, True, True)
        or lift_refusal(t, member, True, True)
    )
    if refusal is not None or _lug_holds(t, member, palm, f1, f2):
        return refusal
    return hold_refusal(t, member, palm, extended=True, finger=f1)


def _lug_holds(t: ObjectType, member: str, palm: str, f1: str, f2: str) -> bool:
    """A lug pinched with the wall behind it (`calibrated.lug_wall`): the wall bears the
    moment about the closing axis, so the whole moment may reach `EXTENDED_TORQUE_LIMIT`
    (stock pots up to 2.2 N m about a lug held)."""
    if not any(
        (o := _blocker(t, member, side)) is not None and lug_wall(t, member, palm, side, o)
        for side in (f1, f2)
    ):
        return False
    gx, gy = t.members[member].box.center_xy
    bx, by = t.body.box.center_xy
    return t.mass * G * math.hypot(gx - bx, gy - by) <= EXTENDED_TORQUE_LIMIT


def object_facts(t: ObjectType, extended: bool = False, calibrated: bool = True) -> set[Fact]:
    """Unary facts of one type: supportive/supportable parts, grasps, lifting. `extended`:
    with the grasps of the extended domain ``utamp2x`` (`utamp_gym.affordances.rim`), and
    if `calibrated` those issue #39 calibrated in physics (`utamp_gym.affordances.calibrated`;
    procedural-v2's goals are drawn and labelled with them)."""
    facts: set[Fact] = set()
    for part in SIDES:
        if is_supportive(t, part):
            facts.add(("isSupportive", t.name, part))
        if is_supportable(t, part):
            facts.add(("isSupportable", t.name, part))
    more = extended and calibrated
    grasps = geometric_grasps(t, more)
    paper = geometric_grasps(t) if more else grasps
    light = {m: liftable_via(t, m) for m in t.members}  # the paper's payload
    heavy_ok = {m: liftable_via(t, m, more) for m in t.members}  # utamp2x's
    any_liftable = any(light[m] for m, *_ in paper if t.members[m].kind != "edge")
    for member, palm, f1, f2 in grasps:
        if t.members[member].kind == "edge" and not light[member] and any_liftable:
            continue  # an edge grasp that cannot carry the object is never useful
        lifts = heavy_ok[member] and (
            holds(t, member, palm, extended, f1) or (more and _lug_holds(t, member, palm, f1, f2))
        )
        if light[member] and not lifts:
            continue  # light enough, but it would turn out of the pads when lifted
        facts.add(("canGraspFrom", t.name, member, palm, f1, f2))
        if lifts:
            facts.add(("canLift", t.name, member))
    if extended:
        for member, palm, f1, f2 in rim_pinches(t, calibrated):
            facts.add(("canGraspFrom", t.name, member, palm, f1, f2))
            facts.add(("canLift", t.name, member))
    if more:  # slid to the table's edge and pinched there (`utamp_gym.affordances.edge`)
        facts |= edge_facts(t)
    return facts


def derive_affordances(
    types: Iterable[ObjectType], extended: bool = False, calibrated: bool = True
) -> frozenset[Fact]:
    """All affordance facts among the given object types (`extended`, `calibrated`: see
    `object_facts`)."""
    types = list(types)
    facts: set[Fact] = set()
    for t in types:
        facts |= object_facts(t, extended, calibrated)
    for t2 in types:
        for p2 in SIDES:
            for t1 in types:
                for p1 in SIDES:
                    if p2p_supportive(t2, p2, t1, p1):
                        facts.add(("isP2PSupportive", p2, t2.name, p1, t1.name))
    for t1 in types:
        graspable = any(f[0] == "canGraspFrom" and f[1] == t1.name for f in facts)
        liftable = any(f[0] == "canLift" and f[1] == t1.name for f in facts)
        if not t1.movable or liftable or not graspable:
            continue
        for t2 in types:
            if t2.movable:
                continue
            for p1 in SIDES:
                for p2 in SIDES:
                    flat = t1.parts[p1].shape == "flat" and t2.parts[p2].shape == "flat"
                    if flat and ("isP2PSupportive", p2, t2.name, p1, t1.name) in facts:
                        facts.add(("canSlide", t1.name, t2.name, p1, p2))
    facts |= edge_slide_facts(types, facts)
    return frozenset(facts)
