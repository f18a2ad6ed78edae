"""Support rules: the parts an object rests on, the parts that carry others, and whether
one object's part carries another's (the paper's assumptions; the grasp and lift rules and
the facts they make are in `utamp_gym.affordances.rules`, which re-exports these).

* a part an object can rest on must be flat (or an open rim) and not a food surface
  (food surfaces are never put face-down), and the object's centre of mass must lie over
  it (a pan whose heavy handle outweighs its shallow body tips onto the handle);
* a part supports others only if it is flat (or a concave dish spanned by the object
  on it) and the object can rest with that part facing up; fixed furniture supports
  on its top only;
* small objects do not support larger ones: on a flat surface the footprint of the
  supported object must fit the surface (on a round one, the circle), with a margin
  inside a rim (a tray's floor, a plate's well) or for an object taller than wide (a glass
  on another's foot tips over); a concave surface (a pan) only
  supports objects whose standing surface spans its opening with a margin (a pan's
  narrower floor would sink into another pan); the supporter's robustness bounds the
  load.
"""

from __future__ import annotations

import math

from utamp_gym.affordances.solids import stand_refusal
from utamp_gym.affordances.why import REFUSED, Refusal
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import OPPOSITE

LOAD_CAPACITY = {"fragile": 0.5, "sturdy": 3.0, "solid": 100.0}  # kg
#: m a side: what is set into a recessed surface clears its rim by this, and what is taller
#: than wide stays this far inside the surface's edge (the robot's pose estimates are a few
#: millimetres off, and a glass landed on the edge of another tips over); what spans a
#: concave opening overlaps its rim so
PLACE_MARGIN = 0.004
SPAN_MARGIN = 0.008


def can_rest_on(t: ObjectType, part: str) -> bool:
    return rest_refusal(t, part, why=False) is None


def rest_refusal(t: ObjectType, part: str, why: bool = True) -> Refusal | None:
    """Why `t` cannot rest on its `part` (None: it can)."""
    attrs = t.parts[part]
    if attrs.shape not in ("flat", "open"):
        if not why:
            return REFUSED
        return Refusal("surface-shape", {"type": t.name, "part": part, "shape": attrs.shape})
    if attrs.food_surface:
        return Refusal("food-surface", {"type": t.name, "part": part}) if why else REFUSED
    return None


def is_supportable(t: ObjectType, part: str) -> bool:
    return supportable_refusal(t, part, why=False) is None


def supportable_refusal(t: ObjectType, part: str, why: bool = True) -> Refusal | None:
    """Why `t` cannot be put down on its `part` (None: it can)."""
    if not t.movable:
        return Refusal("fixed", {"type": t.name}) if why else REFUSED
    return rest_refusal(t, part, why) or stand_refusal(t, part, why)


def is_supportive(t: ObjectType, part: str) -> bool:
    return supportive_refusal(t, part, why=False) is None


def supportive_refusal(t: ObjectType, part: str, why: bool = True) -> Refusal | None:
    """Why `part` of `t` carries nothing (None: it carries things)."""
    shape = t.parts[part].shape
    if not t.movable:
        if part == "on" and shape == "flat":
            return None
        if not why:
            return REFUSED
        return Refusal("fixed-top-only", {"type": t.name, "part": part, "shape": shape})
    if shape not in ("flat", "concave"):
        if not why:
            return REFUSED
        return Refusal("support-shape", {"type": t.name, "part": part, "shape": shape})
    below = rest_refusal(t, OPPOSITE[part], why)
    if below is None or not why:
        return below
    values = {"type": t.name, "part": part, "opposite": OPPOSITE[part], "why": below}
    return Refusal("never-up", values)


def _disc(t: ObjectType, part: str) -> float | None:
    """Diameter of `part` if it is a round face (a cylinder body forms it), else None."""
    body, bbox = t.body.box, t.bbox
    forms = (part == "on" and body.max[2] >= bbox.max[2] - 1e-9) or (
        part == "under" and body.min[2] <= bbox.min[2] + 1e-9
    )
    if t.body.geom != "cylinder" or not forms:
        return None
    size = t.parts[part].size
    extent = (body.max[0] - body.min[0], body.max[1] - body.min[1])
    return float(min(*extent, *(size if size is not None else ())))


def _close(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-8 + 1e-5 * abs(b)  # numpy's isclose


def _flat_refusal(
    t2: ObjectType, p2: str, t1: ObjectType, p1: str, why: bool = True
) -> Refusal | None:
    """Why t1's footprint (resting on p1) does not fit the flat surface p2 of t2 (None: it
    fits). Objects keep their yaw (all x-aligned), so a rectangle is compared axis by axis;
    on a round surface a footprint must fit the circle: a round one by its diameter, any
    other by its diagonal. (Plain floats: the scene generator asks this many thousand
    times.)"""
    footprint = t1.bbox.face_size(p1)
    tall = t1.bbox.max[2] - t1.bbox.min[2] > min(footprint)  # tips if landed off-centre
    recessed = _recessed(t2, p2)
    margin = 2 * PLACE_MARGIN if tall or recessed else 0.0
    disc = _disc(t2, p2)
    if disc is None:
        surface = t2.surface_size(p2)
        if all(f + margin <= s + 1e-9 for f, s in zip(footprint, surface, strict=True)):
            return None
        if not why:
            return REFUSED
        values = {"footprint": footprint, "surface": surface}
        rule = "footprint"
    else:
        own = _disc(t1, p1)
        body, bbox = t1.body.box, t1.bbox
        round_ = own is not None and all(
            _close(body.max[i] - body.min[i], bbox.max[i] - bbox.min[i]) for i in (0, 1)
        )
        size = own if round_ and own is not None else math.hypot(*footprint)
        if size + margin <= disc + 1e-9:
            return None
        if not why:
            return REFUSED
        values = {"size": size, "disc": disc}
        rule = "footprint-disc"
    because = "to clear its rim" if recessed else "as it is taller than wide" if tall else ""
    values.update(type=t1.name, supporter=t2.name, part=p2, margin=margin, margin_why=because)
    return Refusal(rule, values)


def _recessed(t: ObjectType, part: str) -> bool:
    """A surface below the object's top (a tray's floor inside its rims, a plate's well):
    what is set on it must clear the rim."""
    return part == "on" and t.surface_height("on") < t.bbox.max[2] - 1e-6


def p2p_supportive(t2: ObjectType, p2: str, t1: ObjectType, p1: str) -> bool:
    """Can part p2 of t2 stably support t1 resting on its part p1?"""
    return p2p_refusal(t2, p2, t1, p1, why=False) is None


def p2p_refusal(
    t2: ObjectType, p2: str, t1: ObjectType, p1: str, why: bool = True
) -> Refusal | None:
    """Why part p2 of t2 does not carry t1 resting on its part p1 (None: it does)."""
    if t1.name == t2.name:
        return Refusal("same-type", {"type": t1.name}) if why else REFUSED
    capacity = LOAD_CAPACITY[t2.robustness]
    if t1.mass > capacity:
        if not why:
            return REFUSED
        values = {"type": t1.name, "mass": t1.mass, "supporter": t2.name}
        values.update(capacity=capacity, robustness=t2.robustness)
        return Refusal("load-capacity", values)
    refusal = supportive_refusal(t2, p2, why)
    if refusal is None and not t1.movable:
        refusal = Refusal("fixed", {"type": t1.name}) if why else REFUSED
    if refusal is None:
        refusal = rest_refusal(t1, p1, why)
    if refusal is not None:
        return refusal
    if t2.parts[p2].shape == "flat":
        refusal = _flat_refusal(t2, p2, t1, p1, why)
    else:  # a concave surface: the surface the object stands on spans its opening
        standing, opening = t1.surface_size(p1), t2.surface_size(p2)
        span = zip(standing, opening, strict=True)
        if not all(f >= s + 2 * SPAN_MARGIN - 1e-9 for f, s in span):
            if not why:
                return REFUSED
            values = {"type": t1.name, "supporter": t2.name, "part": p2, "margin": SPAN_MARGIN}
            refusal = Refusal("span", {**values, "standing": standing, "opening": opening})
    # t1 is supportable on p1 (the costliest test last)
    return refusal if refusal is not None else stand_refusal(t1, p1, why)
