"""Object bodies from the catalogue: collision primitives, mass, friction, colour, start pose.

The same catalogue data the symbolic layer reads decides the physical shape:

* a cylinder body with a ``round`` top gets a rounded (half-ellipsoid) head, so nothing
  rests on it; a box body with a ``round`` top gets the same kind of cap;
* an ``open`` top makes the body hollow: a ring of thin wall boxes on a flat floor;
* a ``concave`` top gives a flat bottom (the ``under`` part's size) and a low flared rim;
* a ``flat`` top smaller than the body's face becomes a plate with a raised rim around it;
  the plate's top is the part's declared surface ``height`` (scene poses put objects
  there), the rim rises to the body's full height;
* a handle big enough to leave a finger-sized opening becomes a loop of three bars, a
  handle separated from the body by a gap is held by two posts, other members are solid;
* edge members inside the body box are realised by the body itself.

Primitives are in the object frame (origin at the bottom centre of the body). Each body
weighs its catalogue mass (uniform density over its primitives).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from utamp_gym.scene.catalogue import Member, ObjectType
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.model import Pose, Scene

WALL = 0.004  # m, wall thickness of hollow (open-top) bodies
FLOOR = 0.008  # m, floor thickness of hollow bodies
RIM_WALL = 0.003  # m, flared rim thickness of concave bodies
CONCAVE_FLOOR = 0.005  # m, floor thickness of concave bodies
RING_SEGMENTS = 8  # wall boxes of a hollow cylinder
RIM_SEGMENTS = 12  # rim boxes of a concave cylinder
PLATE_RIM = 0.003  # m, rim above the plate when the part declares no surface height
CAP_FRACTION = 0.4  # a round head is at most this fraction of the body height
BAR = 0.008  # m, bar thickness of a loop handle
LOOP_OPENING = (0.015, 0.03)  # m, smallest (outward, vertical) opening of a loop handle
POST = 0.01  # m, width of the posts holding a detached handle bar
EMBED = 0.003  # m, an attached handle reaches this far into the body (no seam)

BODY_PREFIX = "obj/"  # MuJoCo name prefix of object bodies and their geoms
#: sliding friction per material (unknown materials: "default"); torsional and rolling below
FRICTION: Mapping[str, float] = MappingProxyType(
    {"wood": 0.5, "glass": 0.45, "steel": 0.4, "default": 0.5}
)
TORSIONAL, ROLLING = 0.005, 0.0001  # m; torsional acts on handles and edges (condim 4)
SOLREF = (0.01, 1.0)  # 5 dt at dt = 0.002: stiff, still well resolved
SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
#: colours (hex RGBA) per material, each used once per scene, then a generic palette
COLOURS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "wood": ("8c572bff", "dbb073ff", "b3804dff"),
        "glass": ("9ed1f2cc", "b8f2cccc"),
        "steel": ("38383fff", "9e9eadff"),
        "default": ("d94040ff", "408cd9ff", "f2bf33ff", "804db3ff", "4db366ff", "e680b3ff"),
    }
)
ACCENT = "bfbfc7ff"  # metal parts such as a shaker's head


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


def _prim(
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


def _box(name: str, member: str, lo: np.ndarray, hi: np.ndarray) -> Prim:
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    return _prim(name, member, "box", (hi - lo) / 2, (hi + lo) / 2)


def _cylinder(name: str, member: str, xy: np.ndarray, r: float, z0: float, z1: float) -> Prim:
    return _prim(name, member, "cylinder", (r, (z1 - z0) / 2, 0.0), (*xy, (z0 + z1) / 2))


def _cap(name: str, xy: np.ndarray, half: tuple[float, float, float], z: float) -> Prim:
    """Upper half of an ellipsoid centred at height z: a rounded head."""
    return _prim(f"{name}/head", name, "ellipsoid", half, (*xy, z), accent=True)


def _ring(
    member: str,
    xy: np.ndarray,
    bottom: tuple[float, float],
    top: tuple[float, float],
    thick: float,
    n: int,
) -> list[Prim]:
    """Wall boxes whose outer polygon runs from (radius, z) `bottom` to `top` (wider: flared)."""
    (r0, z0), (r1, z1) = bottom, top
    dr, dz = (r1 - r0) * math.cos(math.pi / n), z1 - z0
    length = math.hypot(dr, dz)
    shift = thick * dr / length  # a flared wall's inner face rises this far above its outer
    z0, z1 = (z0, z1 - shift) if shift > 0 else (z0 - shift, z1)
    size = (thick / 2, math.sin(math.pi / n) * max(r0, r1), (z1 - z0) / 2 * length / dz)
    out = []
    for k in range(n):
        phi = 2 * math.pi * k / n
        e = np.array([math.cos(phi), math.sin(phi), 0.0])
        t = np.array([-math.sin(phi), math.cos(phi), 0.0])
        u = (dr * e + np.array([0.0, 0.0, dz])) / length
        normal = np.cross(t, u)  # outward, perpendicular to the wall
        r_mid = (r0 + r1) / 2 * math.cos(math.pi / n)
        centre = np.array([*xy, (z0 + z1) / 2]) + r_mid * e - thick / 2 * normal
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.column_stack([normal, t, u]).ravel())
        out.append(_prim(f"{member}/wall{k:02d}", member, "box", size, centre, quat))
    return out


def _body_prims(t: ObjectType) -> list[Prim]:
    m, name = t.body, t.body.name
    lo, hi = np.asarray(m.box.min), np.asarray(m.box.max)
    xy, size = (lo[:2] + hi[:2]) / 2, hi - lo
    top, bottom = t.parts["on"], t.parts["under"]
    if m.geom == "cylinder":
        r = float(min(size[0], size[1])) / 2
        if top.shape == "round":
            cap = min(r, CAP_FRACTION * size[2])
            return [
                _cylinder(f"{name}/base", name, xy, r, lo[2], hi[2] - cap),
                _cap(name, xy, (r, r, cap), hi[2] - cap),
            ]
        if top.shape == "open":
            z = lo[2] + min(FLOOR, size[2] / 4)
            r_in = r * math.cos(math.pi / RING_SEGMENTS)
            return [
                _cylinder(f"{name}/floor", name, xy, r_in, lo[2], z),
                *_ring(name, xy, (r, z), (r, hi[2]), WALL, RING_SEGMENTS),
            ]
        if top.shape == "concave":
            rb = min(r, bottom.size[0] / 2 if bottom.size is not None else 0.8 * r)
            z = lo[2] + min(CONCAVE_FLOOR, size[2] / 4)
            return [
                _cylinder(f"{name}/floor", name, xy, rb, lo[2], z),
                *_ring(
                    name, xy, (rb + RIM_WALL, (lo[2] + z) / 2), (r, hi[2]), RIM_WALL, RIM_SEGMENTS
                ),
            ]
        return [_cylinder(name, name, xy, r, lo[2], hi[2])]
    if top.shape == "round":
        cap = min(size[0], size[1], 2 * CAP_FRACTION * size[2]) / 2
        return [
            _box(f"{name}/base", name, lo, np.array([*hi[:2], hi[2] - cap])),
            _cap(name, xy, (size[0] / 2, size[1] / 2, cap), hi[2] - cap),
        ]
    usable = np.asarray(top.size if top.size is not None else size[:2], dtype=float)
    hollow = top.shape in ("open", "concave")
    if not hollow and np.all(usable >= size[:2] - 1e-6):
        return [_box(name, name, lo, hi)]
    if hollow:  # an open box: walls (at least WALL thick) on a floor
        usable = np.minimum(usable, size[:2] - 2 * WALL)
        z = lo[2] + min(FLOOR, size[2] / 4)
    else:  # a plate at the usable surface's height, a raised rim around it
        z = top.height if top.height is not None else hi[2] - min(PLATE_RIM, size[2] / 2)
    ilo, ihi = xy - usable / 2, xy + usable / 2
    walls = (  # front/back span the full width, left/right fit between them
        ((ihi[0], lo[1]), (hi[0], hi[1])),
        ((lo[0], lo[1]), (ilo[0], hi[1])),
        ((ilo[0], ihi[1]), (ihi[0], hi[1])),
        ((ilo[0], lo[1]), (ihi[0], ilo[1])),
    )
    out = [_box(f"{name}/plate", name, lo, np.array([hi[0], hi[1], z]))]
    for i, (a, b) in enumerate(walls):
        if b[0] - a[0] > 1e-6 and b[1] - a[1] > 1e-6:
            out.append(_box(f"{name}/rim{i}", name, np.array([*a, z]), np.array([*b, hi[2]])))
    return out


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
    opening = (out_len - BAR, hi[2] - lo[2] - 2 * BAR)
    if m.kind == "handle" and opening[0] >= LOOP_OPENING[0] and opening[1] >= LOOP_OPENING[1]:
        outer = hi[ax] - BAR if sign > 0 else lo[ax]
        bars = []
        for name, z0, z1, a0, a1 in (
            ("top", hi[2] - BAR, hi[2], lo[ax], hi[ax]),
            ("bottom", lo[2], lo[2] + BAR, lo[ax], hi[ax]),
            ("grip", lo[2], hi[2], outer, outer + BAR),
        ):
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


def _rgba(hex_colour: str) -> tuple[float, ...]:
    return tuple(int(hex_colour[i : i + 2], 16) / 255 for i in range(0, 8, 2))


def object_colours(scene: Scene) -> dict[str, tuple[float, ...]]:
    """One colour per object: `rgba` from its type if given, else by material, all distinct."""
    used: set[tuple[float, ...]] = set()
    out = {}
    for o in scene.objects:
        t = scene.type_of(o.name)
        rgba = t.extra.get("rgba")
        if rgba is None:
            options = [_rgba(c) for c in (*COLOURS.get(t.material, ()), *COLOURS["default"])]
            rgba = next((c for c in options if c not in used), options[len(out) % len(options)])
        out[o.name] = tuple(float(v) for v in rgba)
        used.add(out[o.name])
    return out


def add_object_body(
    spec: mujoco.MjSpec, scene: Scene, name: str, pose: Pose, rgba: tuple[float, ...]
) -> tuple[str, ...]:
    """Add object `name` as one free body ``obj/<name>`` at `pose`; return its geom names."""
    t = scene.type_of(name)
    prims = object_prims(t)
    volume = sum(p.volume for p in prims)
    friction = [FRICTION.get(t.material, FRICTION["default"]), TORSIONAL, ROLLING]
    body = spec.worldbody.add_body(
        name=BODY_PREFIX + name, pos=list(pose.position), quat=list(pose.quat)
    )
    body.add_freejoint(name=f"{BODY_PREFIX}{name}/free")
    names = []
    for p in prims:
        geom = body.add_geom(
            name=f"{BODY_PREFIX}{name}/{p.name}",
            type=p.geom_type,
            size=list(p.size),
            pos=list(p.pos),
            quat=list(p.quat),
            rgba=list(_rgba(ACCENT) if p.accent else rgba),
            friction=friction,
            condim=3 if t.members[p.member].kind == "body" else 4,  # see TORSIONAL
            solref=list(SOLREF),
            solimp=list(SOLIMP),
        )
        geom.mass = t.mass * p.volume / volume  # uniform density; the body weighs `t.mass`
        names.append(geom.name)
    return tuple(names)


def _yaw_quat(yaw: float) -> np.ndarray:
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def initial_poses(
    scene: Scene,
    rng: np.random.Generator | None = None,
    pos_noise: float = 0.003,
    yaw_noise_deg: float = 2.0,
) -> dict[str, Pose]:
    """Scene poses plus seeded noise: xy uniform in ±pos_noise, yaw uniform in ±yaw_noise_deg."""
    out = {}
    for o in scene.objects:
        pose = scene.poses[o.name]
        pos, quat = np.asarray(pose.position, dtype=float), np.asarray(pose.quat, dtype=float)
        if rng is not None:
            dx, dy = rng.uniform(-pos_noise, pos_noise, size=2)
            yaw = math.radians(float(rng.uniform(-yaw_noise_deg, yaw_noise_deg)))
            pos = pos + np.array([dx, dy, 0.0])
            q = np.zeros(4)
            mujoco.mju_mulQuat(q, _yaw_quat(yaw), quat)
            quat = q
        out[o.name] = Pose(tuple(pos.tolist()), tuple(quat.tolist()))  # type: ignore[arg-type]
    return out


__all__ = [
    "BODY_PREFIX",
    "FRICTION",
    "ROLLING",
    "SOLIMP",
    "SOLREF",
    "TORSIONAL",
    "Prim",
    "add_object_body",
    "initial_poses",
    "object_colours",
    "object_prims",
]
