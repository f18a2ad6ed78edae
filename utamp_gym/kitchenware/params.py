"""Parameter tables of kitchenware families and the seeded, rounded draw of one instance.

A family declares each parameter once (`Param`, or once per material): its range in the
unit people measure it in (millimetres, kg/m^3, a fraction), the range real products span
where the sampled one is narrower (what the Panda's table and hand hold), what it is and
where the numbers come from (a key of `sources.SOURCES`). `draw` samples an instance of a
family: a pure function of (family, version, seed) on any machine and Python run. The
generator's randomness is a SHAKE-256 digest of ``family/version/seed`` (no hash
randomisation, no global state), read as uniform numbers: one for the material, one for its
density and one per declared parameter, in order (each scaled to its range); lengths are
rounded to 0.1 mm and masses to 1 g before anything is built, so text output is stable.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import numpy as np

from utamp_gym.scene.materials import material

#: how each unit converts to the SI value a builder receives, and its rounding
UNITS: Mapping[str, tuple[float, int]] = {
    "mm": (1e-3, 4),  # to metres, 0.1 mm
    "kg/m3": (1.0, 0),
    "fraction": (1.0, 3),
    "count": (1.0, 0),
}


class Param(NamedTuple):
    """One sampled dimension or property of a family (uniform in [lo, hi])."""

    name: str
    lo: float
    hi: float
    unit: str  # a key of UNITS
    doc: str
    source: str  # a key of utamp_gym.kitchenware.sources.SOURCES
    real: tuple[float, float] | None = None  # what real products span, if wider than sampled
    materials: tuple[str, ...] = ()  # only for these materials (empty: all)

    def applies(self, mat: str) -> bool:
        return not self.materials or mat in self.materials


class Instance(NamedTuple):
    """A drawn instance: SI values by parameter name, its material and its density."""

    family: str
    version: str
    seed: int
    material: str
    density: float  # kg/m^3 of the solid material
    values: Mapping[str, float]

    def __getitem__(self, name: str) -> float:  # type: ignore[override]
        return self.values[name]


class Built(NamedTuple):
    """What a family's builder returns: a type table (catalogue schema, without mass) and the
    volume (m^3) of solid material plus the mass (kg) of any contents."""

    table: dict[str, Any]
    solid_volume: float
    contents_kg: float = 0.0


class Family(NamedTuple):
    """A family of real kitchenware: parameter table, materials and a builder."""

    name: str
    summary: str  # one line
    doc: str  # what it is, how it is modelled, sources
    materials: tuple[tuple[str, float], ...]  # (material, weight)
    params: tuple[Param, ...]
    build: Callable[[Instance], Built]
    sources: tuple[str, ...]  # keys of SOURCES cited by the family as a whole


def uniforms(n: int, *key: object) -> list[float]:
    """`n` numbers uniform in [0, 1), a pure function of the '/'-joined key: 53-bit slices
    of its SHAKE-256 digest (no state, the same on every machine; cheaper than seeding a
    generator for the few numbers an instance needs)."""
    digest = hashlib.shake_256("/".join(str(k) for k in key).encode()).digest(8 * n)
    return [
        (int.from_bytes(digest[8 * i : 8 * i + 8], "little") >> 11) * 2.0**-53 for i in range(n)
    ]


def rng_for(*key: object) -> np.random.Generator:
    """A PCG64 generator seeded from the SHA-256 of the '/'-joined key (machine- and
    run-independent)."""
    digest = hashlib.sha256("/".join(str(k) for k in key).encode()).digest()
    return np.random.Generator(np.random.PCG64(int.from_bytes(digest[:16], "little")))


def rounded(value: float, unit: str) -> float:
    scale, digits = UNITS[unit]
    out = round(value * scale, digits)
    return float(out) if digits else float(int(out))


def draw(family: Family, version: str, seed: int) -> Instance:
    """Sample one instance of `family` (see the module docstring)."""
    # one number for the material, one for its density, one per parameter
    u = uniforms(2 + len(family.params), "utamp-kitchenware", family.name, version, seed)
    total = sum(w for _, w in family.materials)
    mat, edge = family.materials[-1][0], 0.0
    for name, weight in family.materials:
        edge += weight / total
        if u[0] < edge:
            mat = name
            break
    lo, hi = material(mat).density_range
    density = float(round(lo + (hi - lo) * u[1]))
    values: dict[str, float] = {}
    for p, x in zip(family.params, u[2:], strict=True):
        if p.applies(mat):
            values[p.name] = rounded(p.lo + (p.hi - p.lo) * x, p.unit)
    return Instance(family.name, version, seed, mat, density, values)


def extremes(family: Family, mat: str, high: bool) -> Instance:
    """The instance with every parameter at its low (or high) end, for tests of the bodies."""
    lo, hi = material(mat).density_range
    values = {
        p.name: rounded(p.hi if high else p.lo, p.unit) for p in family.params if p.applies(mat)
    }
    return Instance(family.name, "extreme", 0, mat, hi if high else lo, values)


# ------------------------------------------------------------------ volumes (m^3)
def disc(r: float, h: float) -> float:
    return math.pi * r * r * h


def tube(r: float, wall: float, h: float) -> float:
    """A round wall of outer radius r."""
    return math.pi * (r * r - (r - wall) ** 2) * h


def cup(r: float, h: float, wall: float, floor: float) -> float:
    """An open round vessel: a floor and a wall."""
    return disc(r, floor) + tube(r, wall, max(h - floor, 0.0))


def cup_inside(r: float, h: float, wall: float, floor: float) -> float:
    """The volume inside an open round vessel (what contents fill)."""
    return disc(r - wall, max(h - floor, 0.0))


def box_volume(size: tuple[float, float, float]) -> float:
    return size[0] * size[1] * size[2]


def m(value: float) -> float:
    """A length in metres rounded to 0.1 mm (what every coordinate of a generated type is)."""
    return round(value, 4) + 0.0  # + 0.0: no negative zero in the text


def even(value: float) -> float:
    """A length whose half is on the 0.1 mm grid (a centred box's extent and its faces agree)."""
    return 2 * m(value / 2)


def cylinder(r: float, z0: float, z1: float, x: float = 0.0, y: float = 0.0) -> dict[str, Any]:
    return {
        "geom": "cylinder",
        "min": [m(x - r), m(y - r), m(z0)],
        "max": [m(x + r), m(y + r), m(z1)],
    }


def cuboid(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> dict[str, Any]:
    return {"geom": "box", "min": [m(v) for v in lo], "max": [m(v) for v in hi]}


__all__ = [
    "UNITS",
    "Built",
    "Family",
    "Instance",
    "Param",
    "box_volume",
    "cuboid",
    "cup",
    "cup_inside",
    "cylinder",
    "disc",
    "draw",
    "even",
    "extremes",
    "m",
    "rng_for",
    "rounded",
    "tube",
    "uniforms",
]
