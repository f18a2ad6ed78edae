"""Procedural scenes of generated kitchenware and the versioned splits of `procedural-v1`.

A scene is a pure function of (split, scene seed): its objects (a base and 1-5 others, each
an instance of a kitchenware family, `utamp_gym.kitchenware`), their orientations, initial
stacks and table layout are drawn from one generator seeded by a SHA-256 of the split and the
seed. The goal is the paper's: everything in one tower on the scene's base (``goal_base =
"base"``). A split is a fixed list of scene seeds kept in ``assets/procedural/procedural-v1.toml``
with the SHA-256 of its scene files (`split_digest`, and of every 20th scene for quick
checks); scene ``procedural-v1/<split>/NNNN`` is
the NNNN-th seed of the list. The lists were chosen by `select_seeds` (run
``python -m utamp_gym.suites.procedural select``): the first seeds whose goal the rules call
achievable, plus a share (`UNACHIEVABLE_SHARE`) of seeds whose goal they call unachievable,
which planners must report unsolvable.

Splits (`SPLITS`):

* ``train``: 2-5 objects of the training families (`TRAIN_FAMILIES`), instances drawn from
  the training pool of instance seeds;
* ``test-instances``: the same families and counts, new instances (the test pool);
* ``test-families``: at least one object of a family never in train (`HELD_OUT`), new
  instances;
* ``test-count``: 6 objects (more than any train scene) of the training families.

Layouts: the base stands in slot1 of the suites' table (`assets/scenes/layout.toml`), every
other stack in its own slot 2-5, shifted by up to `JITTER` from the slot's position; every
object lies inside its slot, the workspace and `REACH` of the robot's base, and the heights
of all objects add up to at most `MAX_TOTAL_HEIGHT` (a tower of them leaves the hand room
under the workspace's ceiling).
"""

from __future__ import annotations

import hashlib
import math
import sys
from collections.abc import Sequence
from functools import cache, lru_cache
from pathlib import Path
from typing import Any, NamedTuple

import tomli

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.rules import (
    derive_affordances,
    is_supportable,
    is_supportive,
    object_facts,
    p2p_supportive,
)
from utamp_gym.errors import SceneError, UnknownNameError
from utamp_gym.kitchenware import generate
from utamp_gym.kitchenware.params import rng_for
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import Catalogue, ObjectType, load_catalogue, type_to_dict
from utamp_gym.scene.io import scene_from_dict, scene_to_toml
from utamp_gym.scene.model import STANDING_PART, UP_PART, Scene
from utamp_gym.suites.generate import (
    TABLE_TYPE,
    _layout,
    _liftable_from_above,
    _supports,
    tower_achievable,
)

VERSION = "v1"
SUITE = f"procedural-{VERSION}"
SPLITS = ("train", "test-instances", "test-families", "test-count")
SPLIT_SUITES = tuple(f"{SUITE}/{s}" for s in SPLITS)
#: families of the objects on the base (bases are drawn from `BASES`)
TRAIN_FAMILIES = (
    "mug", "tumbler", "bowl", "plate", "food-box", "bottle",
    "frying-pan", "stock-pot", "paddle-board", "utensil",
)  # fmt: skip
HELD_OUT = ("jar", "container", "saucepan", "sheet-pan")
BASES = ("tray", "chopping-board")
HELD_OUT_BASES = ("sheet-pan",)
#: instance seeds: the training pool is [0, 2**31), the test pool [2**31, 2**32)
POOLS = ((0, 2**31), (2**31, 2**32))
BASE_NAME = "base"
OBJECT_NAMES = (BASE_NAME, "obj1", "obj2", "obj3", "obj4", "obj5")
JITTER = 0.03  # m, the base's shift from slot1's position (each axis)
REACH = 0.74  # m from the robot's base (horizontal) to any member's centre
MAX_TOTAL_HEIGHT = 0.42  # m, all objects stacked
ATTEMPTS = 40  # draws of instances, stacks and layouts before giving up
TOWERS = 20  # goal towers tried per seed
LEVEL_ATTEMPTS = 40  # draws of family and instance for one level of a goal tower
MIN_CARRY = 0.07  # m, the narrowest surface a goal tower goes on from (a mug fits)
FREE_SHARE = 0.25  # seeds whose objects are drawn without building a goal tower
UNACHIEVABLE_SHARE = 0.1
SIZES = {"train": 25 * 9, "test-instances": 12 * 9, "test-families": 12 * 9, "test-count": 12 * 9}
SEEDS_FILE = ("procedural", f"procedural-{VERSION}.toml")


class SplitSpec(NamedTuple):
    families: tuple[str, ...]
    bases: tuple[str, ...]
    sizes: tuple[int, ...]  # objects per scene, the base included
    pool: int  # index into POOLS
    new: tuple[str, ...] = ()  # at least one object of these families


SPECS = {
    "train": SplitSpec(TRAIN_FAMILIES, BASES, (2, 3, 4, 5), 0),
    "test-instances": SplitSpec(TRAIN_FAMILIES, BASES, (2, 3, 4, 5), 1),
    "test-families": SplitSpec(
        (*TRAIN_FAMILIES, *HELD_OUT[:3]),
        (*BASES, *HELD_OUT_BASES),
        (2, 3, 4, 5),
        1,
        new=HELD_OUT,
    ),
    "test-count": SplitSpec(TRAIN_FAMILIES, BASES, (6,), 0),
}


class Generated(NamedTuple):
    """One generated scene and what it was made of."""

    scene: Scene
    seed: int
    families: tuple[str, ...]  # per object, scene order (the base first)
    achievable: bool


class NoLayout(Exception):
    """No valid stacks and layout were found for a seed (it is skipped by `select_seeds`)."""


def _check_split(split: str) -> str:
    if split not in SPECS:
        raise UnknownNameError("procedural split", split, SPLITS)
    return split


@cache
def _catalogue() -> Catalogue:
    return load_catalogue()


def _facts(types: Sequence[ObjectType]) -> frozenset[Fact]:
    return derive_affordances([_catalogue()[TABLE_TYPE], *types])


@lru_cache(maxsize=8192)
def _unary_facts(family: str, instance: int) -> frozenset[Fact]:
    """The rules' facts about one generated type alone (grasps, lifting, its parts)."""
    return frozenset(object_facts(generate(family, VERSION, instance, validate=False)))


def _carries(lower: ObjectType, lower_ori: str, upper: ObjectType, upper_ori: str) -> bool:
    up, stand = UP_PART[lower_ori], STANDING_PART[upper_ori]
    return p2p_supportive(lower, up, upper, stand)


def _orientations(facts: frozenset[Fact], tname: str) -> tuple[list[str], bool]:
    """(orientations it can rest in, preferring those it can be picked up in; whether it can
    be picked up at all)."""
    rest = [
        o for o in ("upright", "inverted") if ("isSupportable", tname, STANDING_PART[o]) in facts
    ]
    pick = [o for o in rest if _liftable_from_above(facts, tname, UP_PART[o])]
    return (pick or rest), bool(pick)


def goal_achievable(
    facts: frozenset[Fact],
    kinds: dict[str, tuple[str, str]],
    stacks: Sequence[Sequence[str]],
) -> bool:
    """Can every object end in one tower on the base (the first object of the first stack)?

    `kinds`: object -> (type, orientation). Objects that cannot be picked up must already
    lie in the base's stack (with everything below them, which stays); the others must be
    pickable and stack, in some order, on top of that fixed part (`tower_achievable`)."""
    base_stack = list(stacks[0])
    pickable = {o: _liftable_from_above(facts, t, UP_PART[ori]) for o, (t, ori) in kinds.items()}
    fixed = 0
    for i, o in enumerate(base_stack[1:], start=1):
        if not pickable[o]:
            fixed = i
    prefix = base_stack[: fixed + 1]
    rest = [o for s in stacks for o in s if o not in prefix]
    if not all(pickable[o] for o in rest):
        return False
    return tower_achievable(facts, kinds[prefix[-1]], [kinds[o] for o in rest])


def _draw_objects(
    split: str, seed: int
) -> tuple[Any, list[str], list[str], list[ObjectType], frozenset[Fact], dict[str, str]]:
    """(rng, names, families, types, facts, orientation per name) of a seed's objects.

    Most seeds (1 - `FREE_SHARE`) build a goal tower from the base up: each object, of a
    uniformly drawn family, is redrawn (at most `LEVEL_ATTEMPTS` draws of family and
    instance) until it can be picked up in some orientation (the base: stand upright),
    stand on the one below and, unless it is the top, carry more (`MIN_CARRY`), within the height
    budget; a tower that gets stuck is started again (`TOWERS` times). Its goal is
    achievable. The other seeds
    draw every object freely (these goals are often unachievable: a bowl too heavy to
    pinch, two bottles)."""
    spec = SPECS[split]
    rng = rng_for("utamp-procedural", VERSION, split, seed)
    n = int(spec.sizes[int(rng.integers(len(spec.sizes)))])
    free = bool(rng.random() < FREE_SHARE)
    held_out_at = int(rng.integers(n)) if spec.new else -1
    lo, hi = POOLS[spec.pool]

    def family_for(k: int) -> str:
        if k == held_out_at:
            pool = [f for f in spec.new if (f in HELD_OUT_BASES) == (k == 0)]
        else:
            pool = list(spec.bases if k == 0 else spec.families)
        return str(pool[int(rng.integers(len(pool)))])

    if free:
        families = [family_for(k) for k in range(n)]
        types = [generate(f, VERSION, int(rng.integers(lo, hi)), validate=False) for f in families]
        orient = ["upright"] * n
    else:
        families, types, orient = _goal_tower(rng, n, family_for, (lo, hi))
    facts = _facts(types)
    names = list(OBJECT_NAMES[:n])
    if free:  # orientations it can rest in (picked up in, where possible)
        for k in range(1, n):
            options, _ = _orientations(facts, types[k].name)
            if not options:
                raise NoLayout(f"{types[k].name} cannot rest on the table")
            orient[k] = str(options[int(rng.integers(len(options)))])
    if sum(_height(t) for t in types) > MAX_TOTAL_HEIGHT:
        raise NoLayout("too tall")
    return rng, names, families, types, facts, dict(zip(names, orient, strict=True))


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


def _height(t: ObjectType) -> float:
    return float(t.bbox.max[2] - t.bbox.min[2])


def _place(
    rng: Any, stack: list[str], slot: dict[str, Any], types: dict[str, ObjectType],
    orient: dict[str, str], workspace: dict[str, Any], base: bool,
) -> tuple[float, float] | None:  # fmt: skip
    """A position for the stack's footprint centre where all of it fits in `slot` and the
    workspace: the base's near its slot's position (within `JITTER`), any other stack's
    uniformly over its slot, nearer than `REACH` (objects above are centred on the one
    below; `generate_scene` checks the exact poses)."""
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
    for _ in range(ATTEMPTS):
        x, y = float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1))
        if base or math.hypot(x, y) + far <= REACH + 0.05:
            return round(x, 4) + 0.0, round(y, 4) + 0.0
    return None


def _carries_more(t: ObjectType, orientation: str) -> bool:
    """Its up-facing surface supports and is at least `MIN_CARRY` wide: a tower can go on."""
    up = UP_PART[orientation]
    return is_supportive(t, up) and min(t.surface_size(up)) >= MIN_CARRY


def _goal_tower(
    rng: Any, n: int, family_for: Any, pool: tuple[int, int]
) -> tuple[list[str], list[ObjectType], list[str]]:
    """A goal tower bottom-up (see `_draw_objects`): `TOWERS` tries of `LEVEL_ATTEMPTS` draws
    a level."""
    for _ in range(TOWERS):
        families: list[str] = []
        types: list[ObjectType] = []
        orient: list[str] = []
        budget = MAX_TOTAL_HEIGHT
        for k in range(n):
            for _ in range(LEVEL_ATTEMPTS):
                fam = family_for(k)
                instance = int(rng.integers(*pool))
                t = generate(fam, VERSION, instance, validate=False)
                if _height(t) > budget:
                    continue
                options = [  # cheap tests first: it stands on the one below and carries more
                    o
                    for o in (("upright",) if k == 0 else ("upright", "inverted"))
                    if is_supportable(t, STANDING_PART[o])
                    and (k == 0 or _carries(types[-1], orient[-1], t, o))
                    and (k == n - 1 or _carries_more(t, o))
                ]
                if k > 0 and options:
                    unary = _unary_facts(fam, instance)
                    options = [
                        o for o in options if _liftable_from_above(unary, t.name, UP_PART[o])
                    ]
                if options:
                    families.append(fam)
                    types.append(t)
                    orient.append(str(options[int(rng.integers(len(options)))]))
                    budget -= _height(t)
                    break
            else:
                break  # this tower is stuck: start another
        if len(types) == n:
            return families, types, orient
    raise NoLayout("no instance fits the tower")


def _scene_dict(split: str, index: int, seed: int) -> tuple[dict[str, Any], list[str], bool]:
    rng, names, families, type_list, facts, orient = _draw_objects(split, seed)
    types = dict(zip(names, type_list, strict=True))
    stacks = _draw_stacks(rng, names, types, facts, orient)
    layout = _layout()
    slots = {s["name"]: s for s in layout["slots"]}
    free = ["slot2", "slot3", "slot4", "slot5"]
    objects: list[dict[str, Any]] = []
    for k, stack in enumerate(stacks):
        if k == 0:
            where = "slot1"
            pos = _place(rng, stack, slots[where], types, orient, layout["workspace"], True)
        else:
            pos = None
            for j in rng.permutation(len(free)):
                where = free[int(j)]
                pos = _place(rng, stack, slots[where], types, orient, layout["workspace"], False)
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
        "name": f"{SUITE}/{split}/{index:04d}",
        "description": f"{SUITE} {split} seed {seed}: "
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


def generate_scene(split: str, seed: int, index: int = 0) -> Generated:
    """The scene of `seed` in `split`, named as the `index`-th of the split (`NoLayout` if the
    seed has no valid layout)."""
    data, families, achievable = _scene_dict(_check_split(split), index, seed)
    file = f"<{SUITE} {split} seed {seed}>"
    try:
        scene = scene_from_dict(data, file=file, catalogue=_catalogue())
    except SceneError as exc:  # a drawn layout the scene checks reject: skip the seed
        raise NoLayout(str(exc)) from exc
    for o in scene.objects[1:]:  # the base never moves; every other member within reach
        for member in scene.type_of(o.name).members:
            x, y = scene.world_box(o.name, member).center_xy
            if math.hypot(x, y) > REACH:
                raise NoLayout(f"{o.name}'s {member} out of reach")
    return Generated(scene, seed, tuple(families), achievable)


# ------------------------------------------------------------------ the seed lists
@lru_cache(maxsize=1)
def _seed_table() -> dict[str, Any]:
    return tomli.loads(asset_path(*SEEDS_FILE).read_text())


def split_seeds(split: str) -> tuple[int, ...]:
    """The scene seeds of a split, in scene order."""
    return tuple(int(s) for s in _seed_table()[_check_split(split)]["seeds"])


def split_hash(split: str) -> str:
    """The SHA-256 of the split's scene files kept with its seeds."""
    return str(_seed_table()[_check_split(split)]["sha256"])


@lru_cache(maxsize=4096)
def split_scene(split: str, index: int) -> Generated:
    """The `index`-th scene of a split: from the split's cache file if there is one (see
    `split_scenes`), else generated (only that one)."""
    seeds = split_seeds(split)
    if not 0 <= index < len(seeds):
        raise UnknownNameError("scene", f"{SUITE}/{split}/{index:04d}", split_names(split)[:3])
    cached = _read_cache(split)
    if cached is not None:
        return cached[index]
    return generate_scene(split, seeds[index], index)


def split_scenes(split: str) -> tuple[Generated, ...]:
    """Every scene of a split, in order.

    Generating a split takes seconds (test-count's six-object towers are found by search),
    so the scenes are kept in a cache file per machine, named by the SHA-256 the repository
    keeps for the split: ``$XDG_CACHE_HOME/utamp_gym/procedural-v1-<split>-<sha256>.json``
    (``~/.cache`` without XDG_CACHE_HOME). A new seed list or generator comes with a new
    SHA-256 (`tests/test_procedural.py` regenerates every split, without the cache, and
    compares), hence a new file. The file is written whole, atomically; one that cannot be
    written is simply not kept."""
    cached = _read_cache(split)
    if cached is not None:
        return cached
    scenes = tuple(generate_scene(split, s, i) for i, s in enumerate(split_seeds(split)))
    _write_cache(split, scenes)
    return scenes


def _cache_path(split: str) -> Path:
    import os

    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "utamp_gym" / f"{SUITE}-{split}-{split_hash(split)[:16]}.json"


@lru_cache(maxsize=len(SPLITS))
def _read_cache(split: str) -> tuple[Generated, ...] | None:
    import json

    path = _cache_path(split)
    try:
        records = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if len(records) != len(split_seeds(split)):
        return None
    file = f"<{SUITE} {split} cache {path.name}>"
    return tuple(
        Generated(
            scene_from_dict(r["scene"], file=file, catalogue=_catalogue()),
            int(r["seed"]),
            tuple(r["families"]),
            bool(r["achievable"]),
        )
        for r in records
    )


def _write_cache(split: str, scenes: tuple[Generated, ...]) -> None:
    import json
    import os
    import tempfile

    from utamp_gym.scene.io import scene_to_dict

    path = _cache_path(split)
    records = [
        {"seed": g.seed, "families": list(g.families), "achievable": g.achievable,
         "scene": scene_to_dict(g.scene)}
        for g in scenes
    ]  # fmt: skip
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False) as f:
            json.dump(records, f)
        os.replace(f.name, path)
    except OSError:
        return
    _read_cache.cache_clear()


def split_names(split: str) -> list[str]:
    return [f"{SUITE}/{split}/{i:04d}" for i in range(len(split_seeds(split)))]


def split_digest(split: str, step: int = 1) -> str:
    """SHA-256 over the split's scene files (TOML, in order, each followed by a NUL), each
    generated anew from its seed (never read from the cache); with `step` > 1 over every
    step-th scene only (the quick check kept as ``sample_sha256``)."""
    h = hashlib.sha256()
    seeds = split_seeds(split)
    for i in range(0, len(seeds), step):
        h.update(scene_to_toml(generate_scene(split, seeds[i], i).scene).encode())
        h.update(b"\0")
    return h.hexdigest()


SAMPLE_STEP = 20  # `sample_sha256` covers scenes 0, 20, 40, ...


def sample_hash(split: str) -> str:
    """The SHA-256 of every `SAMPLE_STEP`-th scene file of a split, kept with its seeds."""
    return str(_seed_table()[_check_split(split)]["sample_sha256"])


def parse_name(name: str) -> tuple[str, int] | None:
    """``procedural-v1/train/0042`` -> ("train", 42); None if not such a name."""
    suite, _, rest = name.partition("/")
    split, _, number = rest.rpartition("/")
    if suite != SUITE or split not in SPECS or len(number) != 4 or not number.isdigit():
        return None
    return split, int(number)


# ------------------------------------------------------------------ choosing the seeds
def _planner_agrees(g: Generated) -> bool:
    """Fast Downward with the rules' affordances solves the scene iff it is called achievable."""
    from utamp_gym.planning.methods import plan_scene

    return plan_scene(g.scene, "utamp2-rules", timeout=60.0).solved == g.achievable


def select_seeds(split: str, n: int, share: float = UNACHIEVABLE_SHARE) -> dict[str, Any]:
    """The first seeds (0, 1, ...) with a valid layout, `n` in all of which ``share`` are
    unachievable (the rest achievable); each label is checked against the planner."""
    want_bad = round(n * share)
    want_good = n - want_bad
    good = bad = 0
    seeds: list[int] = []
    skipped = {"layout": 0, "planner disagrees": 0, "share full": 0}
    seed = -1
    while good < want_good or bad < want_bad:
        seed += 1
        try:
            g = generate_scene(split, seed)
        except NoLayout:
            skipped["layout"] += 1
            continue
        if (g.achievable and good >= want_good) or (not g.achievable and bad >= want_bad):
            skipped["share full"] += 1
            continue
        if not _planner_agrees(g):
            skipped["planner disagrees"] += 1
            continue
        seeds.append(seed)
        good += g.achievable
        bad += not g.achievable
    return {"seeds": seeds, "achievable": good, "unachievable": bad, "skipped": skipped}


def _write_seed_file() -> None:
    import tomli_w

    out: dict[str, Any] = {}
    for split in SPLITS:
        chosen = select_seeds(split, SIZES[split])
        out[split] = {
            "seeds": chosen["seeds"],
            "achievable": chosen["achievable"],
            "unachievable": chosen["unachievable"],
        }
        print(split, {k: v for k, v in chosen.items() if k != "seeds"}, file=sys.stderr)
    asset_path(*SEEDS_FILE[:-1]).joinpath(SEEDS_FILE[-1]).write_text(_HEADER + tomli_w.dumps(out))
    _write_digests()


def _write_digests() -> None:
    import tomli_w

    _seed_table.cache_clear()
    split_scene.cache_clear()
    out = dict(_seed_table())
    for split in SPLITS:
        out[split] = {
            **out[split],
            "sha256": split_digest(split),
            "sample_sha256": split_digest(split, SAMPLE_STEP),
        }
    asset_path(*SEEDS_FILE).write_text(_HEADER + tomli_w.dumps(out))
    _seed_table.cache_clear()


_HEADER = """\
# The splits of procedural-v1: fixed lists of scene seeds (utamp_gym.suites.procedural).
# Scene procedural-v1/<split>/NNNN is generate_scene(split, seeds[NNNN]); sha256 is the digest
# of the split's scene files (split_digest), which tests/test_procedural.py regenerates.
# Written by `python -m utamp_gym.suites.procedural select` (do not edit by hand).
"""


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args == ["select"]:
        _write_seed_file()
        return 0
    if args == ["digest"]:
        _write_digests()
        return 0
    if args == ["check"]:
        bad = [s for s in SPLITS if split_digest(s) != split_hash(s)]
        print("ok" if not bad else f"differ: {', '.join(bad)}")
        return 1 if bad else 0
    print("usage: python -m utamp_gym.suites.procedural select|digest|check", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
