"""Which objects a procedural scene holds: families, instances and orientations, drawn freely or as
a goal tower, and whether the goal is achievable."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache, lru_cache
from typing import Any

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.rules import (
    derive_affordances,
    is_supportable,
    is_supportive,
    object_facts,
    p2p_supportive,
)
from utamp_gym.kitchenware import generate
from utamp_gym.kitchenware.params import rng_for
from utamp_gym.scene.catalogue import Catalogue, ObjectType, load_catalogue
from utamp_gym.scene.model import STANDING_PART, UP_PART
from utamp_gym.suites.generate import (
    TABLE_TYPE,
    _liftable_from_above,
    tower_achievable,
)
from utamp_gym.suites.procedural.spec import (
    HELD_OUT_BASES,
    LEVEL_ATTEMPTS,
    MIN_CARRY,
    POOLS,
    TOWERS,
    V1,
    VERSION,
    Config,
    NoLayout,
)


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
    split: str, seed: int, config: Config = V1
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
    spec = config.specs[split]
    rng = rng_for("utamp-procedural", config.version, split, seed)
    n = int(spec.sizes[int(rng.integers(len(spec.sizes)))])
    free = bool(rng.random() < config.free_share)
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
        families, types, orient = _goal_tower(rng, n, family_for, (lo, hi), config.max_height)
    facts = _facts(types)
    names = list(config.names[:n])
    if free:  # orientations it can rest in (picked up in, where possible)
        for k in range(1, n):
            options, _ = _orientations(facts, types[k].name)
            if not options:
                raise NoLayout(f"{types[k].name} cannot rest on the table")
            orient[k] = str(options[int(rng.integers(len(options)))])
    if sum(_height(t) for t in types) > config.max_height:
        raise NoLayout("too tall")
    return rng, names, families, types, facts, dict(zip(names, orient, strict=True))


def _height(t: ObjectType) -> float:
    return float(t.bbox.max[2] - t.bbox.min[2])


def _carries_more(t: ObjectType, orientation: str) -> bool:
    """Its up-facing surface supports and is at least `MIN_CARRY` wide: a tower can go on."""
    up = UP_PART[orientation]
    return is_supportive(t, up) and min(t.surface_size(up)) >= MIN_CARRY


def _goal_tower(
    rng: Any, n: int, family_for: Any, pool: tuple[int, int], max_height: float
) -> tuple[list[str], list[ObjectType], list[str]]:
    """A goal tower bottom-up (see `_draw_objects`): `TOWERS` tries of `LEVEL_ATTEMPTS` draws
    a level."""
    for _ in range(TOWERS):
        families: list[str] = []
        types: list[ObjectType] = []
        orient: list[str] = []
        budget = max_height
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
