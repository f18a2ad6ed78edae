"""Object bodies from the catalogue: collision primitives, mass, friction, colour, start pose.

The same catalogue data the symbolic layer reads decides the physical shape, generically
from the declared attributes (no per-object or per-type-name code). Every declared
dimension is honoured: each member's box, the heights, sizes and centres of the `on`
and `under` parts. The body member takes the shape of the parts it forms (the `on`
part only if it reaches the top of the bounding box, likewise `under`):

* a ``round`` top becomes a rounded (half-ellipsoid) head, so nothing rests on it;
* an ``open`` or ``concave`` top makes the body hollow: a floor and walls around a
  cavity. The walls are as thick as the rim the part's `size` leaves inside the body's
  face (default `WALL`, `RIM_WALL`); a round body's walls flare from the `under` part's
  size at the floor to the full radius at the top (a bowl, a pan), a box's are upright;
* a ``flat`` top smaller than the body's face, or declared below the body's top
  (`height`), becomes a plate at that height with a raised rim around the usable
  surface (its `size` and `center`): a tray's floor inside its rims, a dinner plate's
  well; the rim rises to the body's full height;
* an `under` part smaller than the body's face (not hollow) becomes a foot `FOOT` high;
* a handle big enough to leave a finger-sized opening becomes a loop of three bars, a
  handle separated from the body by a gap is held by two posts, other members are solid
  (boxes or upright cylinders, per `geom`);
* edge members inside the body box are realised by the body itself (a tray's rim, a
  bowl's wall): the catalogue places them where the body has material.

Primitives are in the object frame (origin at the bottom centre of the body). Each body
weighs its catalogue mass (uniform density over its primitives).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from utamp_gym.errors import SimulationError
from utamp_gym.scene.catalogue import Member, ObjectType, PartAttrs
from utamp_gym.scene.materials import DEFAULT, MATERIALS, hex_rgba, material
from utamp_gym.scene.model import Pose, Scene
from utamp_gym.scene.shapes import (
    BAR,
    FLOOR,
    LOOP_OPENING,
    RIM_WALL,
    WALL,
    floor_thickness,
    touch_axis,
)
from utamp_gym.sim.prims import Prim, box, box_walls, cap, ring, slab

PLATE_RIM = 0.003  # m, rim above the plate when the part declares no surface height
FOOT = 0.008  # m, height of a foot (an `under` part smaller than the body's face)
CAP_FRACTION = 0.4  # a round head is at most this fraction of the body height
POST = 0.01  # m, width of the posts holding a detached handle bar
EMBED = 0.003  # m, an attached handle reaches this far into the body (no seam)
TOL = 1e-6  # m, declared dimensions closer than this are equal
FLAT = PartAttrs("flat")

BODY_PREFIX = "obj/"  # MuJoCo name prefix of object bodies and their geoms
TORSIONAL, ROLLING = 0.005, 0.0001  # m; torsional acts on handles and edges (condim 4)
SOLREF = (0.01, 1.0)  # 5 dt at dt = 0.002: stiff, still well resolved
SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
ACCENT = "bfbfc7ff"  # metal parts such as a shaker's head


def _fail(t: ObjectType, what: str) -> SimulationError:
    return SimulationError(f"object type '{t.name}': {what}")


def _body_parts(t: ObjectType) -> tuple[PartAttrs, PartAttrs]:
    """The attributes of the body's own top and bottom faces (flat where another member
    forms that face of the bounding box, e.g. a bottle's neck above its body)."""
    body, bbox = t.body.box, t.bbox
    top = t.parts["on"] if body.max[2] >= bbox.max[2] - TOL else FLAT
    bottom = t.parts["under"] if body.min[2] <= bbox.min[2] + TOL else FLAT
    if bottom.height is not None and abs(bottom.height - body.min[2]) > TOL:
        raise _fail(t, "an `under` surface above the body's bottom is not supported")
    face = body.size[:2]
    for part, attrs in (("on", top), ("under", bottom)):
        if attrs.size is not None and np.any(np.asarray(attrs.size) > face + TOL):
            raise _fail(
                t,
                f"the `{part}` surface {list(attrs.size)} is larger than the body's face "
                f"{face.round(4).tolist()}",
            )
    return top, bottom


def _inner(
    t: ObjectType, part: PartAttrs, half: np.ndarray, default_wall: float, round_: bool
) -> tuple[np.ndarray, np.ndarray]:
    """(centre offset, half-size) of the region inside the body's walls or rim: the part's
    declared usable surface, else the face less `default_wall` on each side."""
    usable = np.asarray(part.size, dtype=float) / 2 if part.size is not None else half
    offset = np.asarray(part.center, dtype=float) if part.center is not None else np.zeros(2)
    if np.all(usable >= half - TOL):  # the full face: walls of the default thickness
        usable, offset = half - default_wall, np.zeros(2)
    if round_ and (np.linalg.norm(offset) > TOL or abs(usable[0] - usable[1]) > TOL):
        raise _fail(t, "a round body's usable top must be a centred circle")
    return offset, usable


def _hollow(t: ObjectType, top: PartAttrs, bottom: PartAttrs) -> list[Prim]:
    """A floor and walls around a cavity (open or concave top)."""
    name, round_ = t.body.name, t.body.geom == "cylinder"
    lo, hi = np.asarray(t.body.box.min), np.asarray(t.body.box.max)
    xy, half = (lo[:2] + hi[:2]) / 2, (hi[:2] - lo[:2]) / 2
    concave = top.shape == "concave"
    default_wall = RIM_WALL if concave else WALL
    z = lo[2] + floor_thickness(concave, hi[2] - lo[2])
    offset, usable = _inner(t, top, half, default_wall, round_)
    floor = half if bottom.size is None else np.minimum(np.asarray(bottom.size) / 2, half)
    if round_:
        r, rb = float(min(half)), float(min(floor))
        wall = r - float(usable[0])
        return [
            slab(f"{name}/floor", name, True, xy, (rb, rb), lo[2], z),
            *ring(name, xy, (rb, z), (r, hi[2]), wall),
        ]
    out = []
    if np.any(floor < half - TOL):  # a foot under the floor
        out.append(slab(f"{name}/foot", name, False, xy, floor, lo[2], lo[2] + FOOT))
        lo = np.array([*lo[:2], lo[2] + FOOT])
        z = max(z, lo[2] + FLOOR / 2)
    out.append(box(f"{name}/floor", name, lo, (*hi[:2], z)))
    inner = (xy + offset - usable, xy + offset + usable)
    return [*out, *box_walls(name, (lo[:2], hi[:2]), inner, z, hi[2], name="wall")]


def _body_prims(t: ObjectType) -> list[Prim]:
    """The body member: hollow, capped, a plate in a rim or solid (see the module doc)."""
    name, round_ = t.body.name, t.body.geom == "cylinder"
    lo, hi = np.asarray(t.body.box.min), np.asarray(t.body.box.max)
    xy, half, height = (lo[:2] + hi[:2]) / 2, (hi[:2] - lo[:2]) / 2, hi[2] - lo[2]
    top, bottom = _body_parts(t)
    if top.shape in ("open", "concave"):
        return _hollow(t, top, bottom)
    out, z0 = [], lo[2]
    if bottom.size is not None and np.any(np.asarray(bottom.size) / 2 < half - TOL):
        foot = min(FOOT, height / 4)
        out.append(
            slab(f"{name}/foot", name, round_, xy, np.asarray(bottom.size) / 2, z0, z0 + foot)
        )
        z0 += foot
    if top.shape == "round":
        head = np.full(2, min(half)) if round_ else half
        c = min(*head, CAP_FRACTION * height)
        return [
            *out,
            slab(f"{name}/base", name, round_, xy, half, z0, hi[2] - c),
            cap(name, name, xy, (head[0], head[1], c), hi[2] - c),
        ]
    full = top.size is None or np.all(np.asarray(top.size) / 2 >= half - TOL)
    at_top = top.height is None or top.height >= hi[2] - TOL
    if top.shape != "flat" or (at_top and (full or top.height is not None)):
        return [*out, slab(name, name, round_, xy, half, z0, hi[2])]
    offset, usable = _inner(t, top, half, WALL, round_)
    z = top.height if top.height is not None else hi[2] - min(PLATE_RIM, height / 2)
    if not z0 < z <= hi[2] + TOL:
        raise _fail(t, f"the `on` surface height {z} lies outside the body ({z0}..{hi[2]})")
    out.append(slab(f"{name}/plate", name, round_, xy, half, z0, z))
    if round_:
        r = float(min(half))
        return [*out, *ring(name, xy, (r, z), (r, hi[2]), r - float(usable[0]))]
    inner = (xy + offset - usable, xy + offset + usable)
    return [*out, *box_walls(name, (lo[:2], hi[:2]), inner, z, hi[2])]


def _member_prims(t: ObjectType, m: Member) -> list[Prim]:
    body = t.body.box
    lo, hi = np.asarray(m.box.min, dtype=float), np.asarray(m.box.max, dtype=float)
    if m.kind == "edge" and body.contains(m.box, tol=1e-6):
        return []  # realised by the body's own walls
    if m.geom == "cylinder":
        return [
            slab(m.name, m.name, True, (lo[:2] + hi[:2]) / 2, (hi[:2] - lo[:2]) / 2, lo[2], hi[2])
        ]
    side = touch_axis(m.box, body)
    if side is None or side[0] == 2:
        return [box(m.name, m.name, lo, hi)]
    ax, sign = side
    gap = (lo[ax] - body.max[ax]) if sign > 0 else (body.min[ax] - hi[ax])
    if gap > 1e-6:  # detached bar: two posts at its ends bridge the gap to the body
        across = 1 - ax
        out = [box(m.name, m.name, lo, hi)]
        for i, end in enumerate((lo[across], hi[across] - POST)):
            plo, phi = lo.copy(), hi.copy()
            plo[across], phi[across] = end, end + POST
            plo[ax], phi[ax] = (body.max[ax], lo[ax]) if sign > 0 else (hi[ax], body.min[ax])
            out.append(box(f"{m.name}/post{i}", m.name, plo, phi))
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
            bars.append(box(f"{m.name}/{name}", m.name, blo, bhi))
        return bars
    return [box(m.name, m.name, lo, hi)]


def object_prims(t: ObjectType) -> list[Prim]:
    """All collision primitives of an object type, in its own frame."""
    out = _body_prims(t)
    for m in t.members.values():
        if m.kind != "body":
            out.extend(_member_prims(t, m))
    return out


def friction_of(material_name: str) -> float:
    """Sliding friction of a material (`utamp_gym.scene.materials`)."""
    return material(material_name).friction


def object_colours(scene: Scene) -> dict[str, tuple[float, ...]]:
    """One colour per object: `rgba` from its type if given, else by material, all distinct."""
    used: set[tuple[float, ...]] = set()
    out = {}
    for o in scene.objects:
        t = scene.type_of(o.name)
        rgba = t.extra.get("rgba")
        if rgba is None:
            own = MATERIALS[t.material].palette if t.material in MATERIALS else ()
            options = [hex_rgba(c) for c in (*own, *DEFAULT.palette)]
            rgba = next((c for c in options if c not in used), options[len(out) % len(options)])
        out[o.name] = tuple(float(v) for v in rgba)
        used.add(out[o.name])
    return out


def add_object_body(
    spec: mujoco.MjSpec,
    scene: Scene,
    name: str,
    pose: Pose,
    rgba: tuple[float, ...],
    *,
    material: str | None = None,
    accent_material: str | None = None,
) -> tuple[str, ...]:
    """Add object `name` as one free body ``obj/<name>`` at `pose`; return its geom names.

    `material` / `accent_material` name MuJoCo materials (their finish) for the object's
    geoms and its accent-coloured ones (`utamp_gym.sim.appearance`)."""
    t = scene.type_of(name)
    prims = object_prims(t)
    volume = sum(p.volume for p in prims)
    friction = [friction_of(t.material), TORSIONAL, ROLLING]
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
            rgba=list(hex_rgba(ACCENT) if p.accent else rgba),
            material=(accent_material if p.accent else material) or "",
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
    "ROLLING",
    "SOLIMP",
    "SOLREF",
    "TORSIONAL",
    "Prim",
    "add_object_body",
    "friction_of",
    "initial_poses",
    "object_colours",
    "object_prims",
]
