"""Object attributes from rendered RGB-D views: the perceived catalogue type of each object.

`perceive_objects(bundle)` is the perceiver's whole interface: a `ViewBundle` (images,
instance masks, camera intrinsics and poses, the robot's own state) in, one
`PerceivedObject` per instance out. It never sees the scene, its types or the simulator's
geoms: the geometry comes from the fused clouds (`shape.fit_shape`), the material from the
pixels (`material.classify_material`), mass and robustness from both.

`PerceivedObject.as_type(name, orientation)` writes what was seen as a catalogue
`ObjectType` in the object's own frame, given how the object stands (the symbolic state's
orientation: the frame of an inverted object is turned a half turn about x). What the rules
then need and no camera sees is filled in by stated assumptions:

* the face an object rests on is never seen: it is **flat** under an upright object or an
  inverted box (packages are closed), and an **open** rim under an inverted round one
  (turned over onto its opening: a mug, a pot), inside walls as thick as its material's;
* a flat top at least `FOOD_SURFACE` wide both ways is a **food surface** (boards, trays,
  plates: never put face-down), and so is a flat well inside a rim however narrow (a dish:
  a small plate, or a well an object standing in it hides part of);
* a body thinner than `THIN_TOP` has a **thin** top where it is narrower than
  `FOOD_SURFACE` (a spatula's blade: nothing rests on it; a slab as thin and wider is a
  board that carries things); a box body lower than `THIN_SIDE` has **thin** sides, a
  round body round ones;
* a narrow part standing on the body's top (a bottle's neck) makes the top **pointy**;
* a rim (an open, concave or well top) on a body too wide for the hand is offered as
  **edges**: a box's (a tray's sides, standing on the table) on the two sides across from
  its handles, else front and back; a round body's front and back, only where it has no
  handles (a pot or a pan is held by them), as strips across its middle with the
  catalogues' span and band (`RIM_SPAN_SHARE`: a plate's rim from its well up, a bowl's
  band `RIM_BAND` deep). An edge ends where the opening or well inside the rim begins;
* a bare flat slab (no members, lower than `THIN_SIDE`, wider than the hand: a board
  without a handle) has the end strips of its longer axis as **edges**, as the catalogues
  declare them (the rules judge whether a finger fits beside them);
* the **mass** is volume x the material's nominal density (`material.estimate_mass`: the
  material in walls of its typical thickness, but a slab's whole volume, `slab`),
  except where that is light enough for the hand to lift (`LIFTABLE`) but the material's
  density range may make it too heavy: then the heaviest plausible mass (`lift_mass`). A
  camera cannot tell those apart, and the cautious reading plans what works either way
  (the object is slid or held by its rims, as its rims were offered, rather than lifted by
  a grasp that may not carry it). A wooden tray's seen material (2.1 l) weighs 0.9-2.3 kg
  over wood's range: it reads 2.3 kg, not the nominal 1.5 kg (its catalogue mass, 3.5 kg,
  is wood of 1.7 t/m^3: no camera sees that).

Members are named by kind and side (``handle-back``, ``edge-left``, ``neck``): the
perceiver does not know the catalogue's names; `utamp_gym.methods.perceived` aligns them to the
declared members by geometry for scoring.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from utamp_gym.contract.views import ViewBundle
from utamp_gym.perception.cloud import Scene3D, fuse
from utamp_gym.perception.confidence import ALT_MIN, packaged_calibration, raw_confidences
from utamp_gym.perception.learned import (
    learned_confidences,
    measurements,
    packaged_attribute_model,
)
from utamp_gym.perception.material import (
    MaterialEstimate,
    appearance_features,
    classify_material,
    estimate_mass,
    shape_class,
)
from utamp_gym.perception.seen import SeenBox, SeenMember, SeenShape, SeenTop
from utamp_gym.perception.shape import fit_shape
from utamp_gym.perception.volumes import THIN_SIDE, mass_areas, shell_area, slab, solid_volume
from utamp_gym.scene.catalogue import Member, ObjectType, PartAttrs
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.materials import material

FOOD_SURFACE = 0.12  # m: a flat top at least this wide both ways is a food surface
THIN_TOP = 0.0125  # m: a body thinner than this has a thin top where narrower than
#: FOOD_SURFACE (a spatula's blade, 6-12 mm thick, 55-90 mm wide; chopping boards are 12-40
#: mm thick, and wider)
#: m: a member this low rests on the support with the body (a spatula's grip; a pan's or a
#: mug's handle starts 1-4 cm up)
GROUNDED = 0.005
GRIPPER_OPENING = 0.08  # m (the rules' Franka hand): wider bodies are not grasped whole
LIFTABLE = 1.5  # kg (the rules' "well below the payload")
SLAB_EDGE, SLAB_EDGE_INSET = 0.0225, 0.02  # m: a bare slab's end strips (`_slab_edges`)
#: a round body's rim edges as the catalogues declare them (`utamp_gym.kitchenware`): a strip
#: across the middle, at most `RIM_HALF_SPAN` either side, a share of the radius (a flat
#: well's rim, a plate's: 0.3; an open vessel's wall, a bowl's: 0.4); an open vessel's band
#: reaches `RIM_BAND` below its rim (the middle of the catalogues' 20-35 mm bands; a camera
#: sees no end to it), a well's rim stands from the well's floor
RIM_HALF_SPAN = 0.04  # m
RIM_SPAN_SHARE = {"well": 0.3, "open": 0.4}
RIM_BAND = 0.0275  # m
OPPOSITE_SIDE = {"front": "back", "back": "front", "left": "right", "right": "left"}
ACROSS = {"front": ("left", "right"), "back": ("left", "right"), "left": ("front", "back")}
ACROSS["right"] = ACROSS["left"]


@dataclass(frozen=True)
class PerceivedObject:
    """One object as perceived: its seen shape, material, mass and world pose."""

    instance: int
    shape: SeenShape
    material: MaterialEstimate
    mass: float  # kg, the nominal estimate or the heaviest plausible (`lift_mass`)
    mass_low: float  # kg, the lightest plausible over the plausible materials
    mass_high: float  # kg, the heaviest plausible
    edges: tuple[SeenMember, ...]
    #: attribute (`methods.attributes.ATTRIBUTES`: material, mass, robustness, members) ->
    #: probability that the chosen value is right (`perception.confidence`)
    confidence: Mapping[str, float] = field(default_factory=dict)
    #: attribute -> the other plausible values, most likely first (materials; robustness
    #: classes; for mass the heaviest plausible mass of each other plausible class, kg)
    alternatives: Mapping[str, tuple] = field(default_factory=dict)

    @property
    def pose(self) -> np.ndarray:
        """4x4 world pose of the seen frame (origin: body footprint centre on its support)."""
        c, s = math.cos(self.shape.yaw), math.sin(self.shape.yaw)
        out = np.eye(4)
        out[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        out[:3, 3] = self.shape.origin
        return out

    @property
    def height(self) -> float:
        """Height of the object's top above its support (m)."""
        boxes = [self.shape.body.box, *(m.box for m in self.shape.members)]
        return max(b.hi[2] for b in boxes)

    def shape_class(self, orientation: str | None = None) -> str:
        """Coarse shape (`material.shape_class`) of the object in its own frame: upright
        unless `orientation` (or the look: a flat top seen over a rim-less body standing
        on a hidden face is read upright)."""
        return shape_class(self.as_type("probe", orientation or "upright"))

    def as_type(self, name: str, orientation: str = "upright") -> ObjectType:
        """The perceived catalogue type in the object's frame (module docstring)."""
        inverted = orientation == "inverted"
        sh = self.shape
        body_top = sh.body.box.hi[2]
        members: dict[str, Member] = {}
        for m in (sh.body, *sh.members, *self.edges):
            box = _canonical(m.box, body_top, inverted)
            side = _canonical_side(m.side, inverted)
            if m.kind == "body":
                key = "body"
            elif m.side == "on":
                key = "foot" if inverted else "neck"
            else:
                key = f"{m.kind}-{side}"
            while key in members:
                key += "-2"
            members[key] = Member(key, "edge" if m.kind == "edge" else m.kind, box, m.geom)
        bbox = _union([m.box for m in members.values()])
        seen_top = _top_part(self, members["body"].box, bbox, inverted)
        hidden = _hidden_part(self, bbox, inverted)
        parts = {"on": hidden, "under": seen_top} if inverted else {"on": seen_top, "under": hidden}
        if inverted:  # the seen top is the canonical bottom: never a food surface
            parts["under"] = parts["under"]._replace(food_surface=False)
        side_shape = (
            "round"
            if sh.body.geom == "cylinder"
            else "thin"
            if sh.body.box.size[2] < THIN_SIDE
            else "flat"
        )
        for side in ("left", "right", "front", "back"):
            parts[side] = PartAttrs(side_shape)
        mat = material(self.material.name)
        return ObjectType(
            name=name,
            mass=round(self.mass, 4),
            material=self.material.name,
            robustness=mat.robustness,
            members=members,
            parts=parts,
            description=f"perceived from RGB-D views (instance {self.instance})",
        )


def _hidden_part(obj: PerceivedObject, bbox: Box, inverted: bool) -> PartAttrs:
    """The face the object rests on (module docstring): flat under an upright object or an
    inverted box (packages are closed); the opening of an inverted round body, inside walls
    as thick as its material's (`Material.wall`). Either is the body's face, centred on the
    body, not on the box a raised handle widens (a pan's base 8 cm off towards its handle
    tipped it over in the rules); a member down on the support (a spatula's grip) rests on
    it too: the face then spans the bounding box."""
    size = _fit2(obj.shape.bottom_size, bbox, "on")
    if not inverted or obj.shape.body.geom != "cylinder":
        grounded = any(m.box.lo[2] <= GROUNDED for m in obj.shape.members)
        return PartAttrs("flat", size, center=None if grounded else (0.0, 0.0))
    wall = material(obj.material.name).wall or 0.0
    inner = tuple(round(max(v - 2 * wall, 0.0), 4) for v in size)
    return PartAttrs("open", inner, center=(0.0, 0.0))  # type: ignore[arg-type]


def _top_part(obj: PerceivedObject, body: Box, bbox: Box, inverted: bool) -> PartAttrs:
    """The seen top of the body as the part facing up (`on` upright, `under` inverted)."""
    sh, top = obj.shape, obj.shape.top
    necked = any(m.side == "on" for m in sh.members)
    part = "under" if inverted else "on"
    if necked:
        return PartAttrs("pointy")
    shape = top.shape
    size = _fit2(top.size, bbox, part)
    if shape == "flat" and sh.body.box.size[2] < THIN_TOP and min(size) < FOOD_SURFACE:
        return PartAttrs("thin")
    height: float | None = None
    center: tuple[float, float] | None = None
    if shape == "flat" and top.height < sh.body.box.hi[2] - 0.004:  # a well inside a rim
        height = sh.body.box.hi[2] - top.height if inverted else top.height
        center = (top.center[0], -top.center[1] if inverted else top.center[1])
        height = float(np.clip(height, bbox.min[2], bbox.max[2]))
    elif shape in ("open", "concave"):
        center = (top.center[0], -top.center[1] if inverted else top.center[1])
    food = shape == "flat" and not inverted and (height is not None or min(size) >= FOOD_SURFACE)
    return PartAttrs(shape, size, food, height, center)


def _fit2(size: tuple[float, float], bbox: Box, part: str) -> tuple[float, float]:
    """A surface size no larger than the bounding box's face (rounded to 0.1 mm)."""
    face = bbox.face_size(part)
    return (round(min(size[0], face[0]), 4), round(min(size[1], face[1]), 4))


def _canonical(box: SeenBox, body_top: float, inverted: bool) -> Box:
    lo, hi = np.asarray(box.lo, dtype=float), np.asarray(box.hi, dtype=float)
    if inverted:  # a half turn about x, the body's seen top becoming z = 0
        lo, hi = (
            np.array([lo[0], -hi[1], body_top - hi[2]]),
            np.array([hi[0], -lo[1], body_top - lo[2]]),
        )
    return Box(tuple(np.round(lo, 5).tolist()), tuple(np.round(hi, 5).tolist()))  # type: ignore[arg-type]


def _canonical_side(side: str, inverted: bool) -> str:
    if inverted and side in ("left", "right"):
        return OPPOSITE_SIDE[side]
    return side


def _union(boxes: list[Box]) -> Box:
    out = boxes[0]
    for b in boxes[1:]:
        out = out.union(b)
    return out


def _edges(shape: SeenShape) -> tuple[SeenMember, ...]:
    """Rim members where the rim is the only grip (module docstring)."""
    top, body = shape.top, shape.body.box
    rimmed = top.visible and (top.shape in ("open", "concave") or top.rim > 0)
    if min(body.size[:2]) <= GRIPPER_OPENING:
        return ()
    if not rimmed:
        return _slab_edges(shape)
    handles = [m.side for m in shape.members if m.kind == "handle" and m.side != "on"]
    round_ = shape.body.geom == "cylinder"
    if handles and round_:  # a pot or pan is held by its handles
        return ()
    sides = ACROSS[handles[0]] if handles else ("front", "back")
    rim = max(top.rim, 0.004)
    # a box's rim stands on the table (a tray's sides); a round one's band starts at the
    # well's floor (a plate), or `RIM_BAND` below the rim of an open vessel (a bowl)
    z0 = 0.0 if not round_ else min(max(top.floor, 0.0), body.hi[2] - 0.005)
    kind = "open" if top.shape == "open" else "well"
    if round_ and kind == "open":
        z0 = max(z0, body.hi[2] - RIM_BAND)
    out = []
    for side in sides:
        ax = 0 if side in ("front", "back") else 1
        across = 1 - ax
        lo, hi = np.asarray(body.lo, float), np.asarray(body.hi, float)
        elo, ehi = lo.copy(), hi.copy()
        inner = _inner_face(top, ax, side in ("front", "left"))
        if side in ("front", "left"):
            elo[ax] = hi[ax] - rim if inner is None else min(inner, hi[ax] - 0.004)
        else:
            ehi[ax] = lo[ax] + rim if inner is None else max(inner, lo[ax] + 0.004)
        if shape.body.geom == "cylinder":
            radius = body.size[across] / 2
            half = min(RIM_HALF_SPAN, RIM_SPAN_SHARE[kind] * radius)
            mid = (lo[across] + hi[across]) / 2
            elo[across], ehi[across] = mid - half, mid + half
        elo[2] = z0
        out.append(SeenMember("edge", side, SeenBox(tuple(elo.tolist()), tuple(ehi.tolist()))))  # type: ignore[arg-type]
    return tuple(out)


def _inner_face(top: SeenTop, ax: int, high: bool) -> float | None:
    """Where the opening or well inside a rim ends on one side along axis `ax` (the rim's
    inner face: the edge member ends where the surface inside it begins, so that a finger
    beside the rim lands on that surface, as it does on the declared types), or None if
    the top shows no opening."""
    if not top.visible or top.rim <= 0 or top.center is None:
        return None
    half = top.size[ax] / 2
    return float(top.center[ax] + half if high else top.center[ax] - half)


def bare_slab(shape: SeenShape) -> bool:
    """A board without a handle: a `slab` without members, wider than the hand."""
    return slab(shape) and not shape.members and min(shape.body.box.size[:2]) > GRIPPER_OPENING


def _slab_edges(shape: SeenShape) -> tuple[SeenMember, ...]:
    """The end strips of a bare flat slab (a board without a handle: no members, a flat
    top, lower than `THIN_SIDE`), `SLAB_EDGE` deep across its longer axis, inset
    `SLAB_EDGE_INSET` from its sides: what the catalogues declare as its edges (the rules
    then judge whether a finger fits beside them)."""
    body = shape.body.box
    if not bare_slab(shape):
        return ()
    ax = 0 if body.size[0] >= body.size[1] else 1
    across = 1 - ax
    out = []
    for side in ("front", "back") if ax == 0 else ("left", "right"):
        lo, hi = np.asarray(body.lo, float), np.asarray(body.hi, float)
        if side in ("front", "left"):
            lo[ax] = hi[ax] - SLAB_EDGE
        else:
            hi[ax] = lo[ax] + SLAB_EDGE
        lo[across] += SLAB_EDGE_INSET
        hi[across] -= SLAB_EDGE_INSET
        out.append(SeenMember("edge", side, SeenBox(tuple(lo.tolist()), tuple(hi.tolist()))))  # type: ignore[arg-type]
    return tuple(out)


def perceive_objects(bundle: ViewBundle, *, prior_yaw: float = 0.0) -> dict[int, PerceivedObject]:
    """Every object instance seen in `bundle`, perceived (module docstring)."""
    scene = fuse(bundle)
    return {
        i: perceive_instance(scene, i, instance_pixels(bundle, i), prior_yaw=prior_yaw)
        for i in sorted(scene.objects)
    }


def instance_pixels(bundle: ViewBundle, instance: int) -> list[tuple[float, np.ndarray]]:
    """(optical axis z, colours (N, 3)) of an instance's pixels in every view with colour."""
    return [
        (float(v.world_from_camera[2, 2]), v.rgb[v.instances == instance])
        for v in bundle.views
        if v.rgb is not None
    ]


def perceive_instance(
    scene: Scene3D,
    instance: int,
    colours: list[tuple[float, np.ndarray]],
    *,
    prior_yaw: float = 0.0,
) -> PerceivedObject:
    """One object of a fused look (`colours`: its pixels per view, `instance_pixels`)."""
    cloud = scene.objects[instance]
    shape = fit_shape(cloud, scene, instance, prior_yaw=prior_yaw)
    provisional = MaterialEstimate("default", {"default": 1.0})
    looks = PerceivedObject(instance, shape, provisional, 1.0, 1.0, 1.0, ())
    cls = looks.shape_class()
    mat = classify_material(colours, cls)
    volume, area = solid_volume(shape), shell_area(shape)
    sheet, walls = mass_areas(shape)
    model = packaged_attribute_model()
    if model is not None and mat.name != "default":  # the learned model (`learned`)
        pred = model.predict(
            measurements(shape, appearance_features(colours), mat.posterior, cls, volume, area)
        )
        mat = MaterialEstimate(max(pred.material, key=pred.material.__getitem__), pred.material)
        mass, low, high = mass_range(mat, volume, sheet)
        if model.mass_head == "rule":  # volume x density of the learned material
            reported = lift_mass(mass, high)  # (material, robustness: the learned posterior)
            conf, alts = raw_confidences(
                mat.posterior, mat.name, reported, volume, walls, shape.covered
            )
        else:
            scale = pred.mass / max(mass, 1e-9)  # the material's density range about it
            reported, low, high = pred.mass, low * scale, high * scale
            conf, alts = learned_confidences(pred, mat.name, shape.covered)
    else:
        mass, low, high = mass_range(mat, volume, sheet)
        reported = lift_mass(mass, high)
        conf, alts = raw_confidences(
            mat.posterior, mat.name, reported, volume, walls, shape.covered
        )
    calibration = packaged_calibration()
    if calibration is not None:  # the learned heads are calibrated already (temperatures)
        mapped = ("members", "mass") if model and model.mass_head == "rule" else ("members",)
        conf = {**conf, **calibration.apply({a: conf[a] for a in mapped})} if model else \
            calibration.apply(conf)  # fmt: skip
    return PerceivedObject(instance, shape, mat, reported, low, high, _edges(shape),
                           conf, alts)  # fmt: skip


def mass_range(mat: MaterialEstimate, volume: float, area: float) -> tuple[float, float, float]:
    """(nominal, lightest, heaviest plausible) mass in kg of the piece: the chosen material's
    nominal and heaviest (`estimate_mass`), the lightest over the materials at least
    `ALT_MIN` likely (each at the low end of its density range)."""
    mass, low, high = estimate_mass(mat.name, volume, area)
    for m, p in mat.posterior.items():
        if p >= ALT_MIN:
            low = min(low, estimate_mass(m, volume, area)[1])
    return mass, low, high


def lift_mass(mass: float, high: float) -> float:
    """The mass a perceived type reports: the nominal one, or the heaviest plausible one
    where the nominal one is `LIFTABLE` but the material's density range leaves that
    undecided (module docstring)."""
    return high if mass <= LIFTABLE < high else mass


__all__ = [
    "PerceivedObject",
    "bare_slab",
    "lift_mass",
    "mass_range",
    "perceive_instance",
    "perceive_objects",
]
