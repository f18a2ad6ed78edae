"""Where a procedural scene's objects stand: initial stacks, positions in the table's slots, and
the assembled scene (`generate_scene`)."""

from __future__ import annotations

import math
from typing import Any

from utamp_gym.affordances.facts import Fact
from utamp_gym.errors import SceneError
from utamp_gym.scene.catalogue import ObjectType, type_to_dict
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.scene.model import Scene
from utamp_gym.suites.generate import (
    _layout,
    _supports,
)
from utamp_gym.suites.procedural.objects import (
    _catalogue,
    _draw_objects,
    goal_achievable,
)
from utamp_gym.suites.procedural.spec import (
    ATTEMPTS,
    BASE_NAME,
    JITTER,
    REACH,
    STACK_GAP,
    V1,
    Config,
    Generated,
    NoLayout,
    _check_split,
)


def _draw_stacks(
    rng: Any, names: list[str], types: dict[str, ObjectType], facts: frozenset[Fact],
    orient: dict[str, str],
) -> list[list[str]]:  # fmt: skip
    """Initial stacks (bottom to top; the base's first), each object on one it can stand on,
    at most four stacks beside the base's, not already the goal."""
    kind = {o: (types[o].name, orient[o]) for o in names}
    for _ in range(ATTEMPTS):
        stacks = [[BASE_NAME]]
        order = [names[1:][int(i)] for i in rng.permutation(len(names) - 1)]
        ok = True
        for o in order:
            tops = [s for s in stacks if _supports(facts, kind[s[-1]], kind[o])]
            fresh = len(stacks) < 5 and _supports(facts, None, kind[o])
            options = len(tops) + fresh
            if not options:
                ok = False
                break
            pick = int(rng.integers(options))
            if pick < len(tops):
                tops[pick].append(o)
            else:
                stacks.append([o])
        if ok and len(stacks) > 1:
            return stacks
    raise NoLayout("no initial stacks")


def _footprint(t: ObjectType, orientation: str) -> tuple[float, float, float, float]:
    """(min x, min y, max x, max y) of the object relative to its footprint centre."""
    box = t.bbox if orientation == "upright" else t.bbox.flipped()
    cx, cy = box.center_xy
    return box.min[0] - cx, box.min[1] - cy, box.max[0] - cx, box.max[1] - cy


def _place(
    rng: Any, stack: list[str], slot: dict[str, Any], types: dict[str, ObjectType],
    orient: dict[str, str], workspace: dict[str, Any], base: bool, taken: list[Box],
) -> tuple[float, float] | None:  # fmt: skip
    """A position for the stack's footprint centre where all of it fits in `slot` and the
    workspace: the base's near its slot's position (within `JITTER`), any other stack's
    uniformly over its slot, nearer than `REACH` and at least `STACK_GAP` from the stacks
    already placed (`taken`, extended with this one's footprint); objects above are centred
    on the one below, and `generate_scene` checks the exact poses."""
    lo = (max(slot["min"][0], workspace["min"][0]), max(slot["min"][1], workspace["min"][1]))
    hi = (min(slot["max"][0], workspace["max"][0]), min(slot["max"][1], workspace["max"][1]))
    feet = [_footprint(types[o], orient[o]) for o in stack]
    x0, y0 = lo[0] - min(f[0] for f in feet), lo[1] - min(f[1] for f in feet)
    x1, y1 = hi[0] - max(f[2] for f in feet), hi[1] - max(f[3] for f in feet)
    if base:
        px, py = slot["position"]
        x0, x1 = max(x0, px - JITTER), min(x1, px + JITTER)
        y0, y1 = max(y0, py - JITTER), min(y1, py + JITTER)
    if x0 > x1 or y0 > y1:
        return None
    far = max(math.hypot(f[i], f[j]) for f in feet for i in (0, 2) for j in (1, 3))
    rel = (min(f[0] for f in feet), min(f[1] for f in feet), max(f[2] for f in feet),
           max(f[3] for f in feet))  # fmt: skip
    for _ in range(ATTEMPTS):
        x, y = float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))
        x, y = round(x, 4) + 0.0, round(y, 4) + 0.0
        rect = Box((x + rel[0], y + rel[1], 0.0), (x + rel[2], y + rel[3], 0.0))
        if not base and math.hypot(x, y) + far > REACH + 0.05:
            continue
        if all(rect.gap_xy(other) >= STACK_GAP for other in taken):
            taken.append(rect)
            return x, y
    return None


def _scene_dict(
    split: str, index: int, seed: int, config: Config = V1
) -> tuple[dict[str, Any], list[str], bool]:
    rng, names, families, type_list, facts, orient = _draw_objects(split, seed, config)
    types = dict(zip(names, type_list, strict=True))
    stacks = _draw_stacks(rng, names, types, facts, orient)
    layout = _layout()
    slots = {s["name"]: s for s in layout["slots"]}
    free = ["slot2", "slot3", "slot4", "slot5"]
    objects: list[dict[str, Any]] = []
    taken: list[Box] = []
    for k, stack in enumerate(stacks):
        if k == 0:
            where = "slot1"
            pos = _place(rng, stack, slots[where], types, orient, layout["workspace"], True, taken)
        else:
            pos = None
            for j in rng.permutation(len(free)):
                where = free[int(j)]
                pos = _place(
                    rng, stack, slots[where], types, orient, layout["workspace"], False, taken
                )
                if pos is not None:
                    break
            if pos is not None:
                free.remove(where)
        if pos is None:
            raise NoLayout("no room for a stack")
        below = where
        for o in stack:
            entry: dict[str, Any] = {
                "name": o,
                "type": types[o].name,
                "on": below,
                "orientation": orient[o],
            }
            if below == where:
                entry["position"] = list(pos)
            objects.append(entry)
            below = o
    kinds = {o: (types[o].name, orient[o]) for o in names}
    achievable = goal_achievable(facts, kinds, stacks)
    data = {
        "name": f"{config.suite}/{split}/{index:04d}",
        "description": f"{config.suite} {split} seed {seed}: "
        + " | ".join(
            "/".join(
                f"{families[names.index(o)]}{'(inv)' if orient[o] == 'inverted' else ''}" for o in s
            )
            for s in stacks
        ),
        "goal_base": BASE_NAME,
        "workspace": layout["workspace"],
        "table": layout["table"],
        "slots": layout["slots"],
        "objects": objects,
        "types": {t.name: type_to_dict(t) for t in sorted(type_list, key=lambda t: t.name)},
    }
    order = [o["name"] for o in objects]
    return data, [families[names.index(o)] for o in order], achievable


def generate_scene(split: str, seed: int, index: int = 0, config: Config = V1) -> Generated:
    """The scene of `seed` in `split`, named as the `index`-th of the split (`NoLayout` if the
    seed has no valid layout); `config` names another version's splits (procedural-v2)."""
    if config is V1:
        _check_split(split)
    data, families, achievable = _scene_dict(split, index, seed, config)
    file = f"<{config.suite} {split} seed {seed}>"
    try:
        scene = scene_from_dict(data, file=file, catalogue=_catalogue())
    except SceneError as exc:  # a drawn layout the scene checks reject: skip the seed
        raise NoLayout(str(exc)) from exc
    for o in scene.objects[1:]:  # the base never moves; every other member within reach
        for member in scene.type_of(o.name).members:
            x, y = scene.world_box(o.name, member).center_xy
            if math.hypot(x, y) > REACH:
                raise NoLayout(f"{o.name}'s {member} out of reach")
    rects = _stack_rects(scene)  # exact: an object above may stand off its support's centre
    roots = sorted(rects)
    for i, a in enumerate(roots):
        for b in roots[i + 1 :]:
            if rects[a].gap_xy(rects[b]) < STACK_GAP:
                raise NoLayout(f"the stacks on {a} and {b} stand too close")
    return Generated(scene, seed, tuple(families), achievable)


def _stack_rects(scene: Scene) -> dict[str, Box]:
    """The box around every stack (all members of its objects), by its bottom object."""
    below = {o.name: o.on for o in scene.objects}
    rects: dict[str, Box] = {}
    for o in scene.objects:
        root = o.name
        while below[root] in below:
            root = below[root]
        for member in scene.type_of(o.name).members:
            box = scene.world_box(o.name, member)
            rects[root] = rects[root].union(box) if root in rects else box
    return rects
