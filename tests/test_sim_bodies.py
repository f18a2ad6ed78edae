"""Simulated bodies match what the catalogues declare, measured by ray casts in MuJoCo.

Every movable type of both catalogues (the paper's kitchen.toml and extra.toml) and every
procedural kitchenware family at both ends of its parameter ranges, in each of its materials
(`utamp_gym.kitchenware.extreme_type`), is built into a world through the normal path
(`build_world`); `mujoco.mj_ray` then measures its top surface at the declared height, the
usable surface's declared size, the cavity of an open or concave top, the footprint and
height of the bounding box, each member's box and the walls behind each edge member, all
within 1 mm.
"""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from utamp_gym.errors import SimulationError
from utamp_gym.kitchenware import FAMILIES, extreme_type
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import Catalogue, ObjectType, load_catalogue
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.sim.bodies import object_prims
from utamp_gym.sim.world import build_world

pytestmark = pytest.mark.physics

TOL = 0.001  # m
EXTREMES = {
    t.name: t
    for name, fam in FAMILIES.items()
    for mat, _ in fam.materials
    for t in (extreme_type(name, mat, False), extreme_type(name, mat, True))
}
CATALOGUE = (
    load_catalogue()
    .merged(load_catalogue(asset_path("objects", "extra.toml")).types)
    .merged(EXTREMES)
)
KINDS = sorted(n for n, t in CATALOGUE.types.items() if t.movable)
SIZED_TOPS = [n for n in KINDS if CATALOGUE[n].parts["on"].shape == "flat"
              and CATALOGUE[n].parts["on"].size is not None]  # fmt: skip
WITH_EDGES = [n for n in KINDS if any(m.kind == "edge" for m in CATALOGUE[n].members.values())]
FAR = 1.0  # m, rays start this far outside the object


class Probe:
    """One object of type `kind` standing alone on the table; rays in its object frame."""

    def __init__(self, t: ObjectType, catalogue: Catalogue = CATALOGUE):
        data = {
            "name": f"probe-{t.name}",
            "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.8, 0.6, 0.7]},
            "slots": [{"name": "slot1", "position": [0.5, 0.0], "size": [0.6, 0.6]}],
            "objects": [{"name": "o", "type": t.name, "on": "slot1"}],
        }
        cat = catalogue.merged({t.name: t})
        world = build_world(scene_from_dict(data, catalogue=cat))
        self.t, self.model, self.data = t, world.model, world.make_data()
        self.origin = np.asarray(world.info.poses["o"].position)
        prims = object_prims(t)  # the geoms are added in this order
        self.member_of = {g: p.member for g, p in zip(world.geom_ids["o"], prims, strict=True)}

    def hit_member(self, start: np.ndarray, direction: np.ndarray) -> tuple[np.ndarray, str] | None:
        """Object-frame point where a ray from `start` (object frame) first meets the
        object (static geoms such as the table are ignored) and the member hit, or None."""
        geom = np.zeros(1, dtype=np.int32)
        d = np.asarray(direction, dtype=float)
        dist = mujoco.mj_ray(self.model, self.data, self.origin + start, d, None, False, -1, geom)
        if dist < 0:
            return None
        return np.asarray(start) + dist * d, self.member_of[int(geom[0])]

    def hit(self, start: np.ndarray, direction: np.ndarray) -> np.ndarray | None:
        found = self.hit_member(start, direction)
        return None if found is None else found[0]

    def down(self, x: float, y: float) -> float | None:
        """Height of the object's top at (x, y), or None if the ray misses it."""
        p = self.hit(np.array([x, y, FAR]), np.array([0.0, 0.0, -1.0]))
        return None if p is None else float(p[2])

    def up(self, x: float, y: float) -> float | None:
        """Height of the object's bottom at (x, y), or None."""
        p = self.hit(np.array([x, y, -FAR]), np.array([0.0, 0.0, 1.0]))
        return None if p is None else float(p[2])


@pytest.fixture(scope="module", params=KINDS)
def probe(request) -> Probe:
    return Probe(CATALOGUE[request.param])


def _grid(lo: np.ndarray, hi: np.ndarray, n: int = 7) -> list[np.ndarray]:
    """Points of an n x n grid over the rectangle lo..hi (2-d), inset 0.5 mm."""
    a = [np.linspace(lo[i] + 5e-4, hi[i] - 5e-4, n) for i in range(2)]
    return [np.array(p) for p in itertools.product(*a)]


def _extent(probe: Probe, box: Box, axis: int, sign: int, member: str | None = None) -> float:
    """How far the object (or only `member`, where rays meet it first) reaches along
    ±axis: the outermost hit of rays across `box`'s section, refined by zooming in on
    the best ray (a flared rim reaches furthest only along its top edge); nan if none."""
    others = [i for i in range(3) if i != axis]
    lo0, hi0 = np.asarray(box.min)[others], np.asarray(box.max)[others]
    lo, hi = lo0, hi0
    best, best_q = -np.inf, None
    for _ in range(4):
        for q in _grid(lo, hi, 9):
            start = np.zeros(3)
            start[others] = q
            start[axis] = sign * FAR
            direction = np.zeros(3)
            direction[axis] = -sign
            found = probe.hit_member(start, direction)
            if found is not None and member in (None, found[1]) and sign * found[0][axis] > best:
                best, best_q = sign * found[0][axis], q
        if best_q is None:
            return float("nan")
        step = (hi - lo) / 8
        lo, hi = np.maximum(lo0, best_q - step), np.minimum(hi0, best_q + step)
    return float(sign * best)


# ------------------------------------------------------------------------- surfaces
def test_top_surface_at_the_declared_height(probe: Probe) -> None:
    t = probe.t
    top, height = t.parts["on"], t.surface_height("on")
    cx, cy = t.surface_center("on")
    centre = probe.down(cx, cy)
    assert centre is not None
    if top.shape in ("open", "concave"):  # a cavity below a rim at the declared height
        body = t.body.box
        assert centre < height - (height - body.min[2]) / 2, "no cavity under the open top"
        r = body.size[0] / 2
        rim = [
            probe.down(body.center[0] + s * (r - f * 0.0005), cy)
            for s in (1, -1)
            for f in range(1, 40)
        ]  # fmt: skip  (0.5 mm steps: sheet-metal walls)
        assert max(h for h in rim if h is not None) == pytest.approx(height, abs=TOL)
    else:
        assert centre == pytest.approx(height, abs=TOL)


@pytest.mark.parametrize("kind", SIZED_TOPS)
def test_usable_surface_has_the_declared_size(kind: str) -> None:
    probe = Probe(CATALOGUE[kind])
    t = probe.t
    top = t.parts["on"]
    assert top.size is not None
    height = t.surface_height("on")
    (cx, cy), half = t.surface_center("on"), np.asarray(top.size) / 2
    face = np.asarray(t.body.box.size[:2]) / 2
    for axis, sign in itertools.product((0, 1), (1, -1)):
        inside, outside = np.array([cx, cy]), np.array([cx, cy])
        inside[axis] += sign * (half[axis] - TOL)
        outside[axis] += sign * (half[axis] + TOL)
        assert probe.down(*inside) == pytest.approx(height, abs=TOL), (axis, sign)
        if half[axis] >= face[axis] - TOL:
            continue
        beside = probe.down(*outside)
        if t.body.box.max[2] >= t.bbox.max[2] - 1e-9:  # a rim stands around the usable surface
            assert beside is not None and beside > height + TOL, (axis, sign, beside)
        else:  # another member forms the top (a jar's lid): the body's top is lower
            assert beside is None or beside < height - TOL, (axis, sign, beside)


def test_bottom_and_standing_footprint(probe: Probe) -> None:
    t = probe.t
    bottom = t.surface_height("under")
    cx, cy = t.surface_center("under")
    assert probe.up(cx, cy) == pytest.approx(bottom, abs=TOL)
    size = t.parts["under"].size
    if size is None or np.all(np.asarray(size) >= t.body.box.size[:2] - 1e-9):
        return
    for axis, sign in itertools.product((0, 1), (1, -1)):
        inside, outside = np.array([cx, cy]), np.array([cx, cy])
        inside[axis] += sign * (size[axis] / 2 - TOL)
        outside[axis] += sign * (size[axis] / 2 + TOL)
        assert probe.up(*inside) == pytest.approx(bottom, abs=TOL)
        assert (probe.up(*outside) or np.inf) > bottom + TOL / 2


def test_footprint_and_height_are_the_bounding_box(probe: Probe) -> None:
    t = probe.t
    bbox = t.bbox
    for axis, sign in itertools.product(range(3), (1, -1)):
        reach = max(_extent(probe, m.box, axis, sign) * sign for m in t.members.values())
        declared = (bbox.max if sign > 0 else bbox.min)[axis]
        assert sign * reach == pytest.approx(declared, abs=TOL), (axis, sign)


# ------------------------------------------------------------------------- members
def test_every_member_fills_its_box(probe: Probe) -> None:
    """Each member's own geometry reaches every face of its box within 1 mm, except the
    face towards the body it is attached to (posts, a handle embedded in the body), and
    faces hidden behind a sibling member."""
    t, body = probe.t, probe.t.body.box
    for m in t.members.values():
        if m.kind == "edge" and body.contains(m.box, tol=1e-6):
            continue  # the body's wall: see test_edges_are_body_material
        for axis, sign in itertools.product(range(3), (1, -1)):
            face = (m.box.max if sign > 0 else m.box.min)[axis]
            reach = _extent(probe, m.box, axis, sign, member=m.name)
            attached = m.kind != "body" and (
                body.min[axis] >= m.box.max[axis] - 1e-9
                if sign > 0
                else body.max[axis] <= m.box.min[axis] + 1e-9
            )
            if attached:
                assert np.isnan(reach) or sign * reach >= sign * face - TOL, (m.name, axis)
                continue
            if np.isnan(reach):  # nothing of m seen: a sibling must stand in front of it
                assert any(
                    o.name != m.name
                    and (o.box.max[axis] > face if sign > 0 else o.box.min[axis] < face)
                    for o in t.members.values()
                ), (m.name, axis, sign)
                continue
            assert reach == pytest.approx(face, abs=TOL), (m.name, axis, sign)


@pytest.mark.parametrize("kind", WITH_EDGES)
def test_edges_are_body_material(kind: str) -> None:
    """An edge member inside the body is wall or rim: the body's top is at the edge's top
    there, and the wall spans the edge across its thin horizontal axis (the face towards a
    cavity as well); or it is the border strip of a solid slab (a board's edge), with solid
    material at the edge's height beside it."""
    probe = Probe(CATALOGUE[kind])
    edges = [m for m in probe.t.members.values() if m.kind == "edge"]
    for m in edges:
        c = m.box.center
        assert probe.down(c[0], c[1]) == pytest.approx(m.box.max[2], abs=TOL), m.name
        axis = int(np.argmin(m.box.size[:2]))
        for sign in (1, -1):  # from outside the wall, then from inside the cavity
            face = (m.box.max if sign > 0 else m.box.min)[axis]
            start = c.copy()
            start[axis] = face + sign * 0.02
            beside = probe.down(start[0], start[1])
            if beside is not None and beside >= m.box.max[2] - TOL:  # a slab's border
                continue
            direction = np.zeros(3)
            direction[axis] = -sign
            p = probe.hit(start, direction)
            assert p is not None and p[axis] == pytest.approx(face, abs=TOL), (m.name, sign)


# ------------------------------------------------------------------------- mass
def test_body_weighs_the_catalogue_mass(probe: Probe) -> None:
    body = probe.model.body("obj/o").id
    assert probe.model.body_mass[body] == pytest.approx(probe.t.mass)


# ------------------------------------------------------------------------- declared heights
def test_a_round_plate_honours_its_surface_height() -> None:
    """A cylinder whose `on` part declares a lower height is a plate with a rim (it was
    once built solid to its full height, so things placed at that height collided)."""
    plate = CATALOGUE["deep-plate"]
    probe = Probe(plate)
    assert probe.down(0.0, 0.0) == pytest.approx(plate.parts["on"].height, abs=TOL)
    assert probe.down(0.095, 0.0) == pytest.approx(plate.bbox.max[2], abs=TOL)


def test_unsupported_declarations_fail_clearly() -> None:
    board = CATALOGUE["cutting-board"]
    too_big = board._replace(
        parts={**board.parts, "on": board.parts["on"]._replace(size=(0.5, 0.5))}
    )
    with pytest.raises(SimulationError, match=r"cutting-board.*larger than the body"):
        object_prims(too_big)
    bowl = CATALOGUE["soup-bowl"]
    off_centre = bowl._replace(
        parts={**bowl.parts, "on": bowl.parts["on"]._replace(center=(0.01, 0.0))}
    )
    with pytest.raises(SimulationError, match=r"soup-bowl.*centred circle"):
        object_prims(off_centre)
