"""An object's material and what it stands on: geometry only (`utamp_gym.affordances.hand`
asks it where the fingers meet material; the rules ask it what stands).

**The object's material** (`solids`): the body member is a box or an upright cylinder; an
open or concave top leaves a cavity inside its usable surface down to its floor
(`utamp_gym.scene.shapes`: the floor the simulator builds, under a flared wall as wide as
the `under` part); a flat top below the body's top or
smaller than its face leaves a well above its surface height; every other member is solid
(edges inside the body are the body's own walls).

**What stands** (`stands_on`): the mass is spread evenly over the material, as the
simulator spreads it, and its centre must lie over the standing surface.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

from utamp_gym.affordances.why import REFUSED, Refusal
from utamp_gym.scene.catalogue import Member, ObjectType, PartAttrs
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.shapes import floor_thickness

STAND_MARGIN = 0.01  # m: the centre of mass stays this far inside the standing surface


class Solid(NamedTuple):
    """A box or upright cylinder of material (object frame), with an optional hole in its
    footprint: ``(cx, cy, hx, hy)``, a rectangle (or a circle of radius hx if round)."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    round: bool = False
    hole: tuple[float, float, float, float] | None = None

    def covers(self, x: float, y: float) -> bool:
        return self.overlaps((x, x), (y, y))

    def overlaps(self, xs: tuple[float, float], ys: tuple[float, float]) -> bool:
        """True if the footprint meets the rectangle `xs` x `ys` (closed; exact)."""
        cx, cy = (self.lo[0] + self.hi[0]) / 2, (self.lo[1] + self.hi[1]) / 2
        if self.round:
            r = min(self.hi[0] - self.lo[0], self.hi[1] - self.lo[1]) / 2
            dx = max(xs[0] - cx, 0.0, cx - xs[1])
            dy = max(ys[0] - cy, 0.0, cy - ys[1])
            if dx * dx + dy * dy > r * r:
                return False
        elif xs[0] > self.hi[0] or xs[1] < self.lo[0] or ys[0] > self.hi[1] or ys[1] < self.lo[1]:
            return False
        if self.hole is None:
            return True
        hx0, hy0, hr, hh = self.hole  # the rectangle lies wholly in the hole: no material
        if self.round:
            far = max(abs(x - hx0) for x in xs) ** 2 + max(abs(y - hy0) for y in ys) ** 2
            return far >= hr * hr
        inside = all(abs(x - hx0) < hr for x in xs) and all(abs(y - hy0) < hh for y in ys)
        return not inside


def _flip(b: tuple[tuple[float, float, float], tuple[float, float, float]]) -> tuple:
    """A half turn about x: y -> -y, z -> -z."""
    lo, hi = b
    return (lo[0], -hi[1], -hi[2]), (hi[0], -lo[1], -lo[2])


def realised_by_body(t: ObjectType, m: Member) -> bool:
    """An edge inside the body's box is the body's own wall or rim."""
    return m.kind == "edge" and t.body.box.contains(m.box, tol=1e-6)


def solids(t: ObjectType, flipped: bool = False) -> tuple[tuple[str, Solid], ...]:
    """(member, solid) material of the object (see the module docstring); `flipped`: the
    object turned upside down (a half turn about x). Cached by what decides it: the
    members and the top and bottom parts."""
    return _solids(tuple(t.members.values()), t.parts["on"], t.parts["under"], flipped)


@lru_cache(maxsize=16_384)
def _solids(
    members: tuple[Member, ...], top: PartAttrs, under: PartAttrs, flipped: bool
) -> tuple[tuple[str, Solid], ...]:
    body = next(m for m in members if m.kind == "body")
    bottom = min(m.box.min[2] for m in members)
    lo, hi = body.box.min, body.box.max
    round_ = body.geom == "cylinder"
    face = (hi[0] - lo[0], hi[1] - lo[1])
    forms_top = hi[2] >= max(m.box.max[2] for m in members) - 1e-9
    out: list[tuple[str, Solid]] = []
    size = top.size if top.size is not None else face
    cx, cy = top.center if top.center is not None else ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2)
    smaller = size[0] < face[0] - 1e-9 or size[1] < face[1] - 1e-9
    hole = (cx, cy, size[0] / 2, size[1] / 2)
    if forms_top and top.shape in ("open", "concave") and smaller:
        floor = lo[2] + floor_thickness(top.shape == "concave", hi[2] - lo[2])
        base = under.size if lo[2] <= bottom + 1e-9 else None
        if round_ and base is not None and min(base) < min(face) - 1e-9:  # a flared wall
            r = min(base) / 2
            mid = ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2)
            out.append(
                (
                    body.name,
                    Solid((mid[0] - r, mid[1] - r, lo[2]), (mid[0] + r, mid[1] + r, floor), True),
                )
            )
        else:
            out.append((body.name, Solid(lo, (hi[0], hi[1], floor), round_)))
        out.append((body.name, Solid(lo, hi, round_, hole)))
    elif (
        forms_top
        and top.shape == "flat"
        and (smaller or (top.height is not None and top.height < hi[2] - 1e-9))
    ):
        surface = top.height if top.height is not None else hi[2]
        out.append((body.name, Solid(lo, (hi[0], hi[1], surface), round_)))
        if smaller:
            out.append((body.name, Solid(lo, hi, round_, hole)))
    else:
        out.append((body.name, Solid(lo, hi, round_)))
    for m in members:
        if m.kind != "body" and not (m.kind == "edge" and body.box.contains(m.box, tol=1e-6)):
            out.append((m.name, Solid(m.box.min, m.box.max, m.geom == "cylinder")))
    if not flipped:
        return tuple(out)
    flip = []
    for name, s in out:
        slo, shi = _flip((s.lo, s.hi))
        hole = None if s.hole is None else (s.hole[0], -s.hole[1], s.hole[2], s.hole[3])
        flip.append((name, Solid(slo, shi, s.round, hole)))
    return tuple(flip)


def _area(s: Solid) -> tuple[float, float, float]:
    """(area, x moment, y moment) of a solid's footprint, its hole taken out."""
    w, d = s.hi[0] - s.lo[0], s.hi[1] - s.lo[1]
    cx, cy = (s.lo[0] + s.hi[0]) / 2, (s.lo[1] + s.hi[1]) / 2
    area = math.pi * min(w, d) ** 2 / 4 if s.round else w * d
    mx, my = area * cx, area * cy
    if s.hole is not None:
        hx, hy = s.hole[2], s.hole[3]
        hole = math.pi * hx * hx if s.round else 4 * hx * hy
        area, mx, my = area - hole, mx - hole * s.hole[0], my - hole * s.hole[1]
    return area, mx, my


def centre_of_mass(t: ObjectType) -> tuple[float, float]:
    """xy of the object's centre of mass with its mass spread evenly over its material
    (`solids`), as the simulator spreads it over the primitives it builds."""
    return _centre_of_mass(solids(t))


@lru_cache(maxsize=16_384)
def _centre_of_mass(material: tuple[tuple[str, Solid], ...]) -> tuple[float, float]:
    total = mx = my = 0.0
    for _, s in material:
        area, ax, ay = _area(s)
        h = s.hi[2] - s.lo[2]
        total, mx, my = total + area * h, mx + ax * h, my + ay * h
    if total <= 0:
        s = material[0][1]
        return (s.lo[0] + s.hi[0]) / 2, (s.lo[1] + s.hi[1]) / 2
    return mx / total, my / total


def stands_on(t: ObjectType, part: str) -> bool:
    """The object's centre of mass lies over its standing surface `part` (``under`` or
    ``on``), `STAND_MARGIN` inside its edge: a pan whose handle outweighs its shallow body
    tips over onto it."""
    return stand_refusal(t, part, why=False) is None


def stand_refusal(t: ObjectType, part: str, why: bool = True) -> Refusal | None:
    """Why `stands_on` refuses (None: it stands; `REFUSED` if not `why`)."""
    x, y = centre_of_mass(t)
    (w, d), (cx, cy) = t.surface_size(part), t.surface_center(part)
    if abs(x - cx) <= w / 2 - STAND_MARGIN and abs(y - cy) <= d / 2 - STAND_MARGIN:
        return None
    if not why:
        return REFUSED
    values = {"type": t.name, "part": part, "offset": (abs(x - cx), abs(y - cy))}
    return Refusal("tips-over", {**values, "half": (w / 2, d / 2), "margin": STAND_MARGIN})


def member_box(t: ObjectType, member: str, flipped: bool) -> Box:
    b = t.members[member].box
    return Box(*_flip((b.min, b.max))) if flipped else b


__all__ = [
    "STAND_MARGIN",
    "Solid",
    "centre_of_mass",
    "member_box",
    "realised_by_body",
    "solids",
    "stand_refusal",
    "stands_on",
]
