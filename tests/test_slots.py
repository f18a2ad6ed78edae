"""The slot rule (`symbolic.slots`) decides as its first, straightforward form did.

`REFERENCE` below is that form (commit 12bffad, the rule's introduction, as reviewed in
bfe7043): every point of a square grid around the slot's position, tested one by one. The
module now tries only the grid points whose x and whose y each pass, and builds the ordered
spots from the points of each axis; these tests hold both to the reference on every packaged
scene and on random slots whose edges sit on, or a hair from, grid points and footprints.
"""

from __future__ import annotations

import math
import random
from functools import cache, lru_cache

import pytest

from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.model import STANDING_PART, Scene, Slot
from utamp_gym.suites import SUITES, suite_scenes
from utamp_gym.suites import procedural as pv
from utamp_gym.symbolic.slots import (
    SPOT_STEP,
    admits,
    beyond_reach_cm,
    footprint_size,
    slot_spots,
    usable_region,
)

PARTS = ("under", "on", "front", "left")


# --------------------------------------------------------------------------- reference
def ref_slot_spots(scene: Scene, slot: Slot) -> tuple[tuple[float, float], ...]:
    return _ref_spots(
        usable_region(scene, slot), (float(slot.position[0]), float(slot.position[1]))
    )


@cache
def _ref_spots(region: Box, position: tuple[float, float]) -> tuple[tuple[float, float], ...]:
    px, py = position
    size = math.hypot(region.max[0] - region.min[0], region.max[1] - region.min[1])
    n = int(size / SPOT_STEP) + 1
    spots = []
    for i in range(-n, n + 1):
        for j in range(-n, n + 1):
            x, y = px + i * SPOT_STEP, py + j * SPOT_STEP
            if (i or j) and all(
                region.min[k] - 1e-9 <= v <= region.max[k] + 1e-9 for k, v in ((0, x), (1, y))
            ):
                spots.append((round(math.hypot(i, j) * SPOT_STEP, 6), x, (x, y)))
    spots.sort(key=lambda s: (s[0], s[1]))
    return ((px, py), *(s[2] for s in spots))


def ref_admits(scene: Scene, slot: Slot, t: ObjectType, part: str) -> str:
    """The reference decision, and how it was reached: ``no`` / ``size`` (side: size only) /
    ``position`` (the first spot) / ``grid`` (a later spot)."""
    region = usable_region(scene, slot)
    w, d = footprint_size(t.bbox, part)
    if w > region.max[0] - region.min[0] + 1e-6 or d > region.max[1] - region.min[1] + 1e-6:
        return "no"
    upright = part == STANDING_PART["upright"]
    if not upright and part != STANDING_PART["inverted"]:
        return "size"
    box = t.bbox if upright else t.bbox.flipped()
    cx, cy = box.center_xy
    sign = 1.0 if upright else -1.0
    centres = [m.box.center_xy for m in t.members.values()]
    members = [(mx - cx, sign * my - cy) for mx, my in centres]
    for k, (x, y) in enumerate(ref_slot_spots(scene, slot)):
        foot = Box((x + box.min[0] - cx, y + box.min[1] - cy, 0.0),
                   (x + box.max[0] - cx, y + box.max[1] - cy, 0.0))  # fmt: skip
        if (
            region.contains_xy(foot, tol=1e-6)
            and beyond_reach_cm((x + mx, y + my) for mx, my in members) == 0
        ):
            return "grid" if k else "position"
    return "no"


# --------------------------------------------------------------------------- cases
@lru_cache(maxsize=1)
def packaged_scenes() -> tuple[Scene, ...]:
    """Every suite scene and every 4th scene of each procedural split."""
    out = [s for suite in SUITES for s in suite_scenes(suite)]
    for split in pv.SPLITS:
        out += [pv.split_scene(split, i).scene for i in range(0, len(pv.split_seeds(split)), 4)]
    return tuple(out)


def all_types() -> list[ObjectType]:
    """Every object type of the packaged scenes, once."""
    types: dict[str, ObjectType] = {}
    for scene in packaged_scenes():
        for o in scene.objects:
            types.setdefault(o.type, scene.type_of(o.name))
    return list(types.values())


def compare(scene: Scene, slot: Slot, types: list[ObjectType], seen: dict[str, int]) -> None:
    assert slot_spots(scene, slot) == ref_slot_spots(scene, slot), slot
    for t in types:
        for part in PARTS:
            how = ref_admits(scene, slot, t, part)
            seen[how] = seen.get(how, 0) + 1
            assert admits(scene, slot, t, part) == (how != "no"), (scene.name, slot, t.name, part)


def test_admits_and_spots_as_the_reference_on_packaged_scenes() -> None:
    seen: dict[str, int] = {}
    for scene in packaged_scenes():
        types = list({o.type: scene.type_of(o.name) for o in scene.objects}.values())
        for slot in scene.slots:
            compare(scene, slot, types, seen)
    # every way of deciding occurs
    assert set(seen) == {"no", "size", "position", "grid"}, seen


def _edge(rng: random.Random, at: float, footprint: float) -> float:
    """A coordinate on, or a hair from, a grid line `at` or `at` + a footprint's size."""
    base = at + rng.choice((0.0, footprint, -footprint))
    return base + rng.choice((0.0, 0.0, 4e-10, -4e-10, 3e-9, -3e-9, 5e-7, -5e-7, 2e-6, -2e-6))


@pytest.mark.parametrize("seed", range(4))
def test_admits_and_spots_as_the_reference_on_random_slots(seed: int) -> None:
    """Slots anywhere on and off the table, some reaching past the workspace, whose edges lie
    on (or within the rule's tolerances of) grid points and footprint edges."""
    rng = random.Random(seed)
    scene = packaged_scenes()[seed * 7]
    types = all_types()
    seen: dict[str, int] = {}
    for k in range(60):
        px, py = rng.uniform(0.2, 0.8), rng.uniform(-0.6, 0.6)
        t = rng.choice(types)
        fw, fd = footprint_size(t.bbox, "under")
        i0, i1 = rng.randint(-12, -1), rng.randint(1, 12)
        j0, j1 = rng.randint(-10, -1), rng.randint(1, 10)
        lo = [px + i0 * SPOT_STEP, py + j0 * SPOT_STEP]
        hi = [px + i1 * SPOT_STEP, py + j1 * SPOT_STEP]
        if k % 2:  # snap edges to grid lines or footprint sizes, within tolerances
            lo = [_edge(rng, lo[0], 0.0), _edge(rng, lo[1], 0.0)]
            hi = [max(_edge(rng, lo[0], fw), lo[0] + 1e-3), max(_edge(rng, lo[1], fd), lo[1])]
            hi = [max(hi[0], _edge(rng, hi[0], 0.0)), max(hi[1], _edge(rng, hi[1], 0.0))]
        if k % 5 == 0:  # the position outside the region
            px = lo[0] - rng.choice((SPOT_STEP, 1e-9, 5e-7))
        slot = Slot(f"slot{k}", (px, py), Box((lo[0], lo[1], 0.0), (hi[0], hi[1], 0.0)))
        compare(scene, slot, types, seen)
    assert {"no", "position", "grid"} <= set(seen), seen
