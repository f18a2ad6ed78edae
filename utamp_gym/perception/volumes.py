"""How much material a seen object holds: its solid volume, its outer shell, the area a
walled piece's mass is reckoned from (`utamp_gym.perception.material.estimate_mass`) and
the pieces that are solid (slabs), from its seen shape (`seen.SeenShape`) alone."""

from __future__ import annotations

import math

import numpy as np

from utamp_gym.perception.seen import SeenShape

THIN_SIDE = 0.055  # m: a box body lower than this has thin sides (a slab: `slab`)


def solid_volume(shape: SeenShape) -> float:
    """Volume (m^3) of the body's envelope less what is seen hollow, plus the members."""
    b, top = shape.body.box.size, shape.top
    h = float(b[2])
    footprint = math.pi * (b[0] / 2) * (b[1] / 2) if shape.body.geom == "cylinder" else b[0] * b[1]
    hollow = 0.0  # an opening hidden under other objects is judged from the outer wall
    if top.shape in ("open", "concave") or (top.visible and top.rim > 0):
        floor = top.floor if top.floor > 0 else min(0.01, h / 4)
        depth = max(h - floor, 0.0)
        area = top.size[0] * top.size[1]
        if shape.body.geom == "cylinder" and top.shape != "flat":
            area = math.pi * top.size[0] * top.size[1] / 4
        hollow = min(area, footprint) * depth
    volume = footprint * h - hollow
    for m in shape.members:
        volume += float(np.prod(m.box.size))
    return max(volume, 0.0)


def shell_area(shape: SeenShape) -> float:
    """Outer surface (m^2) of the body, open where its top is open, and of its members."""
    b = shape.body.box.size
    if shape.body.geom == "cylinder":
        r = float(np.mean(b[:2])) / 2
        side, cap = 2 * math.pi * r * b[2], math.pi * r * r
    else:
        side, cap = 2 * (b[0] + b[1]) * b[2], b[0] * b[1]
    opening = shape.top.shape in ("open", "concave")  # seen, or judged from the outer wall
    area = side + cap + (0.0 if opening else cap)
    for m in shape.members:
        a = m.box.size
        area += 2 * (a[0] * a[1] + a[0] * a[2] + a[1] * a[2])
    return float(area)


def mass_area(shape: SeenShape) -> float:
    """The area of material a walled piece's mass is reckoned from (`estimate_mass`): its
    `shell_area`, but a round body with a flat well inside a rim (a plate) is one dish-shaped
    sheet, its well's floor its underside: its footprint, a fifth more for the rim's slope
    (counting the top and the underside and the outer wall read a 0.45 kg plate as 1.0 kg)."""
    top, b = shape.top, shape.body.box.size
    if shape.body.geom == "cylinder" and top.shape == "flat" and top.visible and top.rim > 0:
        return float(1.2 * math.pi * (b[0] / 2) * (b[1] / 2))
    return shell_area(shape)


def slab(shape: SeenShape) -> bool:
    """A box body lower than `THIN_SIDE` with a flat top seen without a rim: a board, a
    paddle, a utensil's blade. It is cut or moulded solid: its mass is its whole volume's,
    handle and all, whatever the material's typical wall (`Material.wall`)."""
    top = shape.top
    return (
        shape.body.geom == "box"
        and top.shape == "flat"
        and top.visible
        and top.rim <= 0
        and shape.body.box.size[2] < THIN_SIDE
    )


def mass_areas(shape: SeenShape) -> tuple[float, float]:
    """The areas of material (m^2) a seen piece's mass and its mass classes are reckoned
    from (`material.estimate_mass`, `confidence.raw_confidences`): `mass_area` and
    `shell_area`, or inf for a `slab` (solid: its whole volume is material)."""
    if slab(shape):
        return math.inf, math.inf
    return mass_area(shape), shell_area(shape)


__all__ = ["THIN_SIDE", "mass_area", "mass_areas", "shell_area", "slab", "solid_volume"]
