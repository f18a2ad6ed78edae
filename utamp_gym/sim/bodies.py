"""Collision primitives of an object type, derived from its catalogue members and part shapes.

The same catalogue data the symbolic layer reads decides the physical shape:

* a cylinder body with a ``round`` top gets a rounded (half-ellipsoid) head, so nothing
  rests on it; a box body with a ``round`` top gets the same kind of cap;
* an ``open`` top makes the body hollow: a ring of thin wall boxes on a flat floor;
* a ``concave`` top gives a flat bottom (the ``under`` part's size) and a low flared rim;
* a ``flat`` top smaller than the body's face becomes a plate with a raised rim around it;
* a handle big enough to leave a finger-sized opening becomes a loop of three bars, a
  handle separated from the body by a gap is held by two posts, other members are solid;
* edge members inside the body box are realised by the body itself.

Everything is expressed in the object frame (origin at the bottom centre of the body).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.scene.catalogue import Member, ObjectType
from utamp_gym.scene.geometry import Box

WALL = 0.004  # m, wall thickness of hollow (open-top) bodies
FLOOR = 0.008  # m, floor thickness of hollow bodies
RIM_WALL = 0.003  # m, flared rim thickness of concave bodies
CONCAVE_FLOOR = 0.005  # m, floor thickness of concave bodies
RING_SEGMENTS = 12  # wall boxes of a hollow cylinder
RIM_SEGMENTS = 16  # rim boxes of a concave cylinder
PLATE_RIM = 0.003  # m, how far a raised rim stands above its plate (see module notes)
CAP_FRACTION = 0.4  # a round head is at most this fraction of the body height
BAR = 0.008  # m, bar thickness of a loop handle
LOOP_OPENING = (0.015, 0.03)  # m, smallest (outward, vertical) opening of a loop handle
POST = 0.01  # m, width of the posts holding a detached handle bar
EMBED = 0.003  # m, an attached handle reaches this far into the body (no seam)
GRASP_WIDTH = 0.08  # m, members narrower than the open gripper get torsional friction


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

    def aabb(self) -> Box:
        """Axis-aligned bounds in the object frame (exact for boxes, tight for the rest)."""
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, np.asarray(self.quat, dtype=float))
        half = np.asarray(self.size)
        if self.shape == "cylinder":
            half = np.array([half[0], half[0], half[1]])
        ext = np.abs(rot.reshape(3, 3)) @ half
        c = np.asarray(self.pos)
        return Box(tuple((c - ext).tolist()), tuple((c + ext).tolist()))


def _box(name: str, member: str, lo: np.ndarray, hi: np.ndarray, **kw: object) -> Prim:
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    half = tuple(((hi - lo) / 2).tolist())
    return Prim(name, member, "box", half, tuple(((hi + lo) / 2).tolist()), **kw)  # type: ignore[arg-type]


def _cylinder(name: str, member: str, xy: np.ndarray, radius: float, z0: float, z1: float) -> Prim:
    return Prim(name, member, "cylinder", (radius, (z1 - z0) / 2, 0.0),
                (float(xy[0]), float(xy[1]), (z0 + z1) / 2))


def _ring(member: str, xy: np.ndarray, r0: float, r1: float, z0: float, z1: float,
          thick: float, n: int) -> list[Prim]:
    """Wall boxes whose outer polygon runs from radius r0 at z0 to r1 at z1 (r1 > r0 flares)."""
    half_t = math.sin(math.pi / n)  # tangential half-width per unit radius
    dr, dz = (r1 - r0) * math.cos(math.pi / n), z1 - z0
    length = math.hypot(dr, dz)
    nz = thick / 2 * abs(dr) / length  # a tilted box's corners reach this far past its ends
    z0, z1 = z0 + nz, z1 - nz
    out = []
    for k in range(n):
        phi = 2 * math.pi * k / n
        e = np.array([math.cos(phi), math.sin(phi), 0.0])
        t = np.array([-math.sin(phi), math.cos(phi), 0.0])
        u = (dr * e + dz * np.array([0.0, 0.0, 1.0])) / length
        normal = np.cross(t, u)  # outward, perpendicular to the wall
        r_mid = (r0 + r1) / 2 * math.cos(math.pi / n)
        centre = np.array([xy[0], xy[1], (z0 + z1) / 2]) + r_mid * e - thick / 2 * normal
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.column_stack([normal, t, u]).ravel())
        size = (thick / 2, half_t * max(r0, r1), (z1 - z0) / 2 * length / dz)
        out.append(Prim(f"{member}/wall{k:02d}", member, "box", size, tuple(centre.tolist()),
                        tuple(quat.tolist())))
    return out


def _body_prims(t: ObjectType) -> list[Prim]:
    m = t.body
    lo, hi = np.asarray(m.box.min), np.asarray(m.box.max)
    xy, size = (lo[:2] + hi[:2]) / 2, hi - lo
    top, bottom = t.parts["on"], t.parts["under"]
    cap = min(size[0], size[1], CAP_FRACTION * size[2] * 2) / 2
    if m.geom == "cylinder":
        r = float(min(size[0], size[1])) / 2
        if top.shape == "round":
            cap = min(r, CAP_FRACTION * size[2])
            return [_cylinder(f"{m.name}/base", m.name, xy, r, lo[2], hi[2] - cap),
                    Prim(f"{m.name}/head", m.name, "ellipsoid", (r, r, cap),
                         (float(xy[0]), float(xy[1]), float(hi[2] - cap)), accent=True)]
        if top.shape == "open":
            floor = min(FLOOR, size[2] / 4)
            return [_cylinder(f"{m.name}/floor", m.name, xy, r * math.cos(math.pi / RING_SEGMENTS),
                              lo[2], lo[2] + floor),
                    *_ring(m.name, xy, r, r, lo[2] + floor, hi[2], WALL, RING_SEGMENTS)]
        if top.shape == "concave":
            rb = bottom.size[0] / 2 if bottom.size is not None else 0.8 * r
            floor = min(CONCAVE_FLOOR, size[2] / 4)
            return [_cylinder(f"{m.name}/floor", m.name, xy, min(rb, r), lo[2], lo[2] + floor),
                    *_ring(m.name, xy, min(rb, r) + RIM_WALL, r, lo[2] + floor / 2, hi[2],
                           RIM_WALL, RIM_SEGMENTS)]
        return [_cylinder(m.name, m.name, xy, r, lo[2], hi[2])]
    if top.shape == "round":
        cap = min(size[0], size[1], 2 * CAP_FRACTION * size[2]) / 2
        return [_box(f"{m.name}/base", m.name, lo, np.array([*hi[:2], hi[2] - cap])),
                Prim(f"{m.name}/head", m.name, "ellipsoid", (size[0] / 2, size[1] / 2, cap),
                     (float(xy[0]), float(xy[1]), float(hi[2] - cap)), accent=True)]
    usable = np.asarray(top.size if top.size is not None else size[:2])
    hollow = top.shape in ("open", "concave")
    if hollow or np.any(usable < size[:2] - 1e-6):
        rim = size[2] - min(FLOOR, size[2] / 4) if hollow else min(PLATE_RIM, size[2] / 2)
        if hollow:  # walls as thick as the margin the usable size leaves, else WALL
            usable = np.minimum(usable, size[:2] - 2 * WALL)
        ilo, ihi = xy - usable / 2, xy + usable / 2
        z = hi[2] - rim
        walls = [  # front/back span the full width, left/right fit between them
            (np.array([ihi[0], lo[1], z]), hi),
            (lo, np.array([ilo[0], hi[1], hi[2]])),
            (np.array([ilo[0], ihi[1], z]), np.array([ihi[0], hi[1], hi[2]])),
            (np.array([ilo[0], lo[1], z]), np.array([ihi[0], ilo[1], hi[2]])),
        ]
        walls[1][0][2] = z
        out = [_box(f"{m.name}/plate", m.name, lo, np.array([*hi[:2], z]))]
        for i, (a, b) in enumerate(walls):
            if np.all(b - a > 1e-6):
                out.append(_box(f"{m.name}/rim{i}", m.name, a, b))
        return out
    return [_box(m.name, m.name, lo, hi)]


def _touch_axis(a: Box, b: Box, tol: float = 1e-6) -> tuple[int, int] | None:
    """(axis, sign) if box `a` lies beside `b` along one axis (touching or apart), else None."""
    for ax in range(3):
        others = [i for i in range(3) if i != ax]
        if not all(a.min[i] < b.max[i] and b.min[i] < a.max[i] for i in others):
            continue
        if a.min[ax] >= b.max[ax] - tol:
            return ax, 1
        if a.max[ax] <= b.min[ax] + tol:
            return ax, -1
    return None


def _member_prims(t: ObjectType, m: Member) -> list[Prim]:
    body = t.body.box
    lo, hi = np.asarray(m.box.min, dtype=float), np.asarray(m.box.max, dtype=float)
    if m.kind == "edge" and body.contains(m.box, tol=1e-6):
        return []  # realised by the body's own walls
    if m.geom == "cylinder":
        r = float(min(hi[:2] - lo[:2])) / 2
        return [_cylinder(m.name, m.name, (lo[:2] + hi[:2]) / 2, r, lo[2], hi[2])]
    side = _touch_axis(m.box, body)
    if side is None or side[0] == 2:
        return [_box(m.name, m.name, lo, hi)]
    ax, sign = side
    gap = (lo[ax] - body.max[ax]) if sign > 0 else (body.min[ax] - hi[ax])
    if gap > 1e-6:  # detached bar: two posts at its ends bridge the gap to the body
        across = 1 - ax
        out = [_box(m.name, m.name, lo, hi)]
        for i, end in enumerate((lo[across], hi[across] - POST)):
            plo, phi = lo.copy(), hi.copy()
            plo[across], phi[across] = end, end + POST
            plo[ax], phi[ax] = (body.max[ax], lo[ax]) if sign > 0 else (hi[ax], body.min[ax])
            out.append(_box(f"{m.name}/post{i}", m.name, plo, phi))
        return out
    inner = 0 if sign > 0 else 1  # the face that touches the body: reach into it
    (lo if inner == 0 else hi)[ax] -= sign * EMBED
    out_len = hi[ax] - lo[ax] - EMBED
    if m.kind == "handle" and out_len - BAR >= LOOP_OPENING[0] and hi[2] - lo[2] - 2 * BAR >= (
        LOOP_OPENING[1]
    ):
        outer = hi[ax] - BAR if sign > 0 else lo[ax]
        bars = []
        for name, z0, z1, a0, a1 in (("top", hi[2] - BAR, hi[2], lo[ax], hi[ax]),
                                     ("bottom", lo[2], lo[2] + BAR, lo[ax], hi[ax]),
                                     ("grip", lo[2], hi[2], outer, outer + BAR)):
            blo, bhi = lo.copy(), hi.copy()
            blo[2], bhi[2], blo[ax], bhi[ax] = z0, z1, a0, a1
            bars.append(_box(f"{m.name}/{name}", m.name, blo, bhi))
        return bars
    return [_box(m.name, m.name, lo, hi)]


def object_prims(t: ObjectType) -> list[Prim]:
    """All collision primitives of an object type, in its own frame."""
    out = _body_prims(t)
    for m in t.members.values():
        if m.kind != "body":
            out.extend(_member_prims(t, m))
    return out


def member_is_graspable(t: ObjectType, member: str) -> bool:
    """Members a closed gripper can span (handles, edges, slim bodies) need torsional friction."""
    m = t.members[member]
    return m.kind != "body" or float(min(m.box.size[:2])) <= GRASP_WIDTH


__all__ = ["Prim", "member_is_graspable", "object_prims"]
