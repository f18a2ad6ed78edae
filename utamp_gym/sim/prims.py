"""Collision primitives in an object's frame, and the few solids bodies are built from.

A `Prim` is one MuJoCo geom (box, vertical cylinder or ellipsoid) in the object frame.
The builders here know nothing about catalogues: slabs (a disc or a box between two
heights), walls around a footprint (a ring of boxes for a round footprint, four boxes
for a rectangular one) and rounded heads. Round walls are polygons whose flat outer
faces touch the declared circle on the x and y axes, so the footprint's extents are
exactly the declared ones (the corners stand out by at most `MAX_BULGE`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike

MAX_BULGE = 0.003  # m, how far the corners of a round wall's polygon stand out of its circle
MIN_SEGMENTS = 8  # boxes of a round wall, at least (always a multiple of 4)


@dataclass(frozen=True)
class Prim:
    """One collision primitive in the object frame; `size` uses MuJoCo's half-sizes."""

    name: str
    member: str
    shape: str  # "box" | "cylinder" | "ellipsoid"
    size: tuple[float, float, float]
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    accent: bool = False  # drawn in the accent colour (e.g. a shaker's metal head)

    @property
    def volume(self) -> float:
        a, b, c = self.size
        if self.shape == "box":
            return 8.0 * a * b * c
        if self.shape == "cylinder":
            return 2.0 * math.pi * a * a * b
        return 4.0 / 3.0 * math.pi * a * b * c

    @property
    def geom_type(self) -> mujoco.mjtGeom:
        return {
            "box": mujoco.mjtGeom.mjGEOM_BOX,
            "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
            "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        }[self.shape]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Object-frame axis-aligned bounds (exact for boxes, upright cylinders, ellipsoids)."""
        half = np.asarray(self.size, dtype=float)
        if self.shape == "cylinder":
            half = np.array([self.size[0], self.size[0], self.size[1]])
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, np.asarray(self.quat, dtype=float))
        ext = np.abs(rot.reshape(3, 3)) @ half
        return np.asarray(self.pos) - ext, np.asarray(self.pos) + ext


def prim(
    name: str,
    member: str,
    shape: str,
    size: ArrayLike,
    pos: ArrayLike,
    quat: ArrayLike = (1.0, 0.0, 0.0, 0.0),
    accent: bool = False,
) -> Prim:
    def f(v: ArrayLike) -> tuple[float, ...]:
        return tuple(float(x) for x in np.asarray(v, dtype=float))

    return Prim(name, member, shape, f(size), f(pos), f(quat), accent)  # type: ignore[arg-type]


def box(name: str, member: str, lo: ArrayLike, hi: ArrayLike) -> Prim:
    """A box between corners `lo` and `hi`."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    return prim(name, member, "box", (hi - lo) / 2, (hi + lo) / 2)


def slab(
    name: str, member: str, round_: bool, xy: ArrayLike, half: ArrayLike, z0: float, z1: float
) -> Prim:
    """A disc (radius: the smaller half-extent) or a box over `xy` ± `half`, from z0 to z1."""
    xy, half = np.asarray(xy, dtype=float), np.asarray(half, dtype=float)
    if round_:
        r = float(min(half))
        return prim(name, member, "cylinder", (r, (z1 - z0) / 2, 0.0), (*xy, (z0 + z1) / 2))
    return box(name, member, (*(xy - half), z0), (*(xy + half), z1))


def cap(name: str, member: str, xy: ArrayLike, half: tuple[float, float, float], z: float) -> Prim:
    """A rounded head: the upper half of an ellipsoid centred at height z stands out."""
    return prim(f"{name}/head", member, "ellipsoid", half, (*np.asarray(xy), z), accent=True)


def segments(radius: float) -> int:
    """Boxes in a round wall of `radius`: corners stand out at most `MAX_BULGE`."""
    need = math.pi * math.sqrt(max(radius, 0.0) / (2 * MAX_BULGE))
    return max(MIN_SEGMENTS, 4 * math.ceil(need / 4))


def ring(
    member: str,
    xy: ArrayLike,
    bottom: tuple[float, float],
    top: tuple[float, float],
    thick: float,
    n: int | None = None,
) -> list[Prim]:
    """A round wall of `n` boxes, `thick` thick, whose outer faces run from (radius, z)
    `bottom` to `top` (a wider top flares out). The outer faces are tangent to the circle
    (walls face +x, +y, -x, -y) and reach both radii exactly; the wall's highest point is
    at the top's z, its lowest at the bottom's z (a flared wall's inner face stands above
    its outer one, so the outer face ends a little lower)."""
    (r0, z0), (r1, z1) = bottom, top
    n = segments(max(r0, r1)) if n is None else n
    lo, hi = z0, z1
    for _ in range(6):  # the slope depends on the trimmed height: a few fixed-point steps
        dr, dz = r1 - r0, hi - lo
        length = math.hypot(dr, dz)
        shift = thick * dr / length  # the inner face stands this much above the outer
        lo, hi = (z0, z1 - shift) if shift > 0 else (z0 - shift, z1)
    dr, dz = r1 - r0, hi - lo
    length = math.hypot(dr, dz)
    size = (thick / 2, math.tan(math.pi / n) * max(r0, r1), length / 2)
    centre_xy = np.asarray(xy, dtype=float)
    out = []
    for k in range(n):
        phi = 2 * math.pi * k / n
        e = np.array([math.cos(phi), math.sin(phi), 0.0])
        t = np.array([-math.sin(phi), math.cos(phi), 0.0])
        u = (dr * e + np.array([0.0, 0.0, dz])) / length
        normal = np.cross(t, u)  # outward, perpendicular to the wall
        mid = np.array([*centre_xy, (lo + hi) / 2]) + (r0 + r1) / 2 * e
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.column_stack([normal, t, u]).ravel())
        out.append(
            prim(f"{member}/wall{k:02d}", member, "box", size, mid - thick / 2 * normal, quat)
        )
    return out


def box_walls(
    member: str,
    outer: tuple[np.ndarray, np.ndarray],
    inner: tuple[np.ndarray, np.ndarray],
    z0: float,
    z1: float,
    name: str = "rim",
) -> list[Prim]:
    """Four vertical walls filling the xy region between rectangle `outer` and the
    rectangle `inner` inside it (each given as (lo, hi) corners), from z0 to z1."""
    (lo, hi), (ilo, ihi) = outer, inner
    walls = (  # front/back span the full width, left/right fit between them
        ((ihi[0], lo[1]), (hi[0], hi[1])),
        ((lo[0], lo[1]), (ilo[0], hi[1])),
        ((ilo[0], ihi[1]), (ihi[0], hi[1])),
        ((ilo[0], lo[1]), (ihi[0], ilo[1])),
    )
    out = []
    for i, (a, b) in enumerate(walls):
        if b[0] - a[0] > 1e-6 and b[1] - a[1] > 1e-6:
            out.append(box(f"{member}/{name}{i}", member, (*a, z0), (*b, z1)))
    return out


__all__ = [
    "MAX_BULGE",
    "Prim",
    "box",
    "box_walls",
    "cap",
    "prim",
    "ring",
    "segments",
    "slab",
]
