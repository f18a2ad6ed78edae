"""The benchmark suites, enumerated deterministically: the paper's two and `extra`.

**pick-place**: the tray plus a non-empty subset of {salt, mug, board, pan}
(2 <= n <= 5). For every allowed orientation of each object (upright if it can rest
on its bottom, inverted if it can rest on its top; either only if the hand can then
grasp and lift it from above) and every partition of the objects
into stacks in which each object can stand on the one below under the ground-truth
affordances (the tray only on the table), the stacks are put in table slots: the
tray's stack in slot1, the others in slots 2-5 in catalogue order of their bottom
object. A configuration is kept if

* it is not already the goal (all objects in one tower on the tray), and
* the goal tower is achievable: some order of the non-tray objects exists in which
  each, in its fixed orientation, can stand on the one below, starting on the tray.
  This is a combinatorial check on the affordance facts; the planner is never run.

**sliding**: the pick-place configurations whose tray starts empty, with the tray moved
to the far end of slot1 (partly outside the workspace) and a free space in front of
it, so `slide-support` is needed before anything can be stacked on it.

**extra**: as pick-place, with the six objects of `assets/objects/extra.toml` (not in
the paper) added to the paper's four: the tray plus one or two objects, at least one
of them new. The new types' affordances come from the rule parser (there is no
hand-written truth for them), the paper objects' from the ground truth; the scenes
carry the new types in their `types` table, so an exported scene file is complete.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from functools import cache
from typing import Any, NamedTuple

import tomli  # see utamp_gym.scene.fields

from utamp_gym.affordances.facts import Fact, fact_types, packaged_ground_truth
from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import Catalogue, load_catalogue, type_to_dict
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.scene.model import STANDING_PART, UP_PART, Scene

SUITES = ("pick-place", "sliding", "extra")
#: instance name -> catalogue type, in catalogue order
MOVABLES: tuple[tuple[str, str], ...] = (
    ("salt", "salt-shaker"),
    ("mug", "glass-mug"),
    ("board", "cutting-board"),
    ("pan", "frying-pan"),
)
#: the objects beyond the paper (types in `assets/objects/extra.toml`), in catalogue order
EXTRA_MOVABLES: tuple[tuple[str, str], ...] = (
    ("bowl", "soup-bowl"),
    ("plate", "deep-plate"),
    ("teabox", "tea-box"),
    ("bottle", "oil-bottle"),
    ("pot", "stock-pot"),
    ("spatula", "wooden-spatula"),
)
EXTRA_CATALOGUE = "extra.toml"
TRAY = ("tray", "wooden-tray")
TABLE_TYPE = "kitchen-table"


class SuiteSpec(NamedTuple):
    """How a suite is enumerated: which objects, how many, from where."""

    movables: tuple[tuple[str, str], ...]
    sizes: tuple[int, ...]  # how many movable objects (besides the tray) a scene has
    sliding: bool = False
    new: tuple[str, ...] = ()  # instance names of which every scene has at least one


SPECS = {
    "pick-place": SuiteSpec(MOVABLES, (1, 2, 3, 4)),
    "sliding": SuiteSpec(MOVABLES, (1, 2, 3, 4), sliding=True),
    "extra": SuiteSpec(
        (*MOVABLES, *EXTRA_MOVABLES), (1, 2), new=tuple(n for n, _ in EXTRA_MOVABLES)
    ),
}


class SuiteStats(NamedTuple):
    """How many configurations were enumerated, dropped and kept."""

    suite: str
    enumerated: int
    trivial: int
    unachievable: int
    kept: int
    kept_by_n: dict[int, int]


def _supports(
    facts: frozenset[Fact], lower: tuple[str, str] | None, upper: tuple[str, str]
) -> bool:
    """Can `upper` (type, orientation) stand on `lower` (None = the table)?"""
    utype, uori = upper
    if lower is None:
        return ("isP2PSupportive", "on", TABLE_TYPE, STANDING_PART[uori], utype) in facts
    ltype, lori = lower
    return ("isP2PSupportive", UP_PART[lori], ltype, STANDING_PART[uori], utype) in facts


def _liftable_from_above(facts: frozenset[Fact], tname: str, up: str) -> bool:
    """Can the hand grasp `tname` with the palm on its up-facing part `up` and lift it?"""
    return any(
        f[0] == "canGraspFrom"
        and f[1] == tname
        and f[3] == up
        and ("canLift", tname, f[2]) in facts
        for f in facts
    )


def _orientations(facts: frozenset[Fact], tname: str) -> list[str]:
    """Orientations `tname` can rest in and be picked up from (an upside-down bowl rests
    on its rim, but the hand cannot reach its rim through the floor)."""
    return [
        ori
        for ori in ("upright", "inverted")
        if ("isSupportable", tname, STANDING_PART[ori]) in facts
        and _liftable_from_above(facts, tname, UP_PART[ori])
    ]


def _partitions(items: Sequence[str]) -> Iterator[list[list[str]]]:
    """All set partitions of `items` (each block unordered, in a canonical order)."""
    if not items:
        yield []
        return
    first, rest = items[0], items[1:]
    for part in _partitions(rest):
        yield [[first], *part]
        for i in range(len(part)):
            yield [*part[:i], [first, *part[i]], *part[i + 1 :]]


def tower_achievable(
    facts: frozenset[Fact], base: tuple[str, str], others: Sequence[tuple[str, str]]
) -> bool:
    """Can `others` (type, orientation) be ordered so that each stands on the one below?

    A depth-first search that abandons an order as soon as one object cannot stand on the
    one below (not every permutation is tried)."""
    if not others:
        return True
    return any(
        _supports(facts, base, upper)
        and tower_achievable(facts, upper, [*others[:i], *others[i + 1 :]])
        for i, upper in enumerate(others)
        if upper not in others[:i]  # an equal object already tried in this position
    )


def _stacks(block: Sequence[str], on: set[tuple[str | None, str]]) -> list[list[str]]:
    """Every order of `block` (bottom->top) in which the bottom object stands on the table
    and each other on the one below (`(lower, upper) in on`, lower None = the table), in
    `itertools.permutations` order; a depth-first search that prunes at the first failure."""
    stacks: list[list[str]] = []

    def extend(stack: list[str], rest: Sequence[str]) -> None:
        if not rest:
            stacks.append(stack)
            return
        below = stack[-1] if stack else None
        for i, obj in enumerate(rest):
            if (below, obj) in on:
                extend([*stack, obj], [*rest[:i], *rest[i + 1 :]])

    extend([], block)
    return stacks


def _layout() -> dict[str, Any]:
    return tomli.loads(asset_path("scenes", "layout.toml").read_text())


def _configurations(
    facts: frozenset[Fact], spec: SuiteSpec
) -> Iterator[tuple[dict[str, str], list[list[str]]]]:
    """(orientation per object, stacks bottom->top) for every physically valid stacking."""
    types = dict((*spec.movables, TRAY))
    orientations = {m: _orientations(facts, types[m]) for m, _ in spec.movables}
    for n_movable in spec.sizes:
        for subset in itertools.combinations([m for m, _ in spec.movables], n_movable):
            if spec.new and not set(subset) & set(spec.new):
                continue
            for choice in itertools.product(*(orientations[m] for m in subset)):
                orient = dict(zip(subset, choice, strict=True)) | {TRAY[0]: "upright"}
                names = [TRAY[0], *subset]
                # the support relation among these objects, looked up once per pair
                on = {
                    (lower, upper)
                    for upper in names
                    for lower in (None, *names)
                    if lower != upper
                    and _supports(
                        facts,
                        None if lower is None else (types[lower], orient[lower]),
                        (types[upper], orient[upper]),
                    )
                }
                block_stacks: dict[tuple[str, ...], list[list[str]]] = {}  # blocks recur
                for blocks in _partitions(names):
                    for block in blocks:
                        if tuple(block) not in block_stacks:
                            block_stacks[tuple(block)] = _stacks(block, on)
                    stacks_per_block = [block_stacks[tuple(block)] for block in blocks]
                    for stacks in itertools.product(*stacks_per_block):
                        yield orient, list(stacks)


def _scene_dict(
    name: str, orient: dict[str, str], stacks: list[list[str]], spec: SuiteSpec
) -> dict[str, Any]:
    layout = _layout()
    suite = layout["suite"]
    sliding = spec.sliding
    types = dict((*spec.movables, TRAY))
    order = {m: i for i, (m, _) in enumerate(spec.movables)}
    tray_stack = next(s for s in stacks if s[0] == TRAY[0])
    others = sorted((s for s in stacks if s[0] != TRAY[0]), key=lambda s: order[s[0]])
    free_slots = [s["name"] for s in layout["slots"] if s["name"] != suite["tray_slot"]]
    objects = []
    for slot, stack in [(suite["tray_slot"], tray_stack), *zip(free_slots, others, strict=False)]:
        below = slot
        for obj in stack:
            entry: dict[str, Any] = {
                "name": obj,
                "type": types[obj],
                "on": below,
                "orientation": orient[obj],
            }
            if obj == TRAY[0]:
                key = "sliding_tray_position" if sliding else "pick_place_tray_position"
                entry["position"] = suite[key]
            objects.append(entry)
            below = obj
    data: dict[str, Any] = {
        "name": name,
        "description": " | ".join(
            "/".join(f"{o}{'(inv)' if orient[o] == 'inverted' else ''}" for o in s)
            for s in [tray_stack, *others]
        ),
        "workspace": layout["workspace"],
        "table": layout["table"],
        "slots": layout["slots"],
        "objects": objects,
    }
    if sliding:
        data["spaces"] = layout["spaces"]
    return data


def extra_catalogue() -> Catalogue:
    """The object types beyond the paper (`assets/objects/extra.toml`)."""
    return load_catalogue(asset_path("objects", EXTRA_CATALOGUE))


def suite_facts(suite: str) -> frozenset[Fact]:
    """The affordances a suite is enumerated with: the ground truth, and for the types
    without hand-written truth (the extra catalogue's) the rule parser's facts."""
    facts = packaged_ground_truth()
    if suite != "extra":
        return facts
    # lazy: keeps `utamp plan` from loading utamp_gym.affordances.rules
    from utamp_gym.affordances.rules import derive_affordances  # numpy: off `utamp plan`'s path

    new = extra_catalogue()
    types = [*load_catalogue().types.values(), *new.types.values()]
    derived = derive_affordances(types)
    return facts | {f for f in derived if set(fact_types(f)) & set(new.types)}


Configuration = tuple[dict[str, str], list[list[str]]]  # (orientation per object, stacks)


@cache
def _kept(suite: str) -> tuple[tuple[Configuration, ...], SuiteStats]:
    """The suite's configurations in their stable order, and its statistics (no scenes are
    built: `_scene` builds one on demand)."""
    spec = SPECS[suite]
    facts = suite_facts(suite)
    types = dict((*spec.movables, TRAY))
    kept: list[Configuration] = []
    enumerated = trivial = unachievable = 0
    achievable: dict[tuple[tuple[str, str], ...], bool] = {}  # by the objects' orientations
    for orient, stacks in _configurations(facts, spec):
        if spec.sliding and next(s for s in stacks if s[0] == TRAY[0]) != [TRAY[0]]:
            continue
        enumerated += 1
        if len(stacks) == 1:
            trivial += 1
            continue
        others = tuple((types[o], orient[o]) for o in orient if o != TRAY[0])
        if others not in achievable:
            achievable[others] = tower_achievable(facts, (TRAY[1], "upright"), others)
        if not achievable[others]:
            unachievable += 1
            continue
        kept.append((orient, stacks))
    kept.sort(key=lambda c: (len(c[0]), sorted(c[0].items()), [s for s in c[1]]))
    by_n: dict[int, int] = {}
    for orient, _ in kept:  # every object of a configuration has an orientation
        by_n[len(orient)] = by_n.get(len(orient), 0) + 1
    stats = SuiteStats(
        suite, enumerated, trivial, unachievable, len(kept), dict(sorted(by_n.items()))
    )
    return tuple(kept), stats


@cache
def _catalogue() -> Catalogue:
    """The packaged catalogue, shared by every suite scene."""
    return load_catalogue()


@cache
def _scene(suite: str, index: int) -> Scene:
    spec = SPECS[suite]
    orient, stacks = _kept(suite)[0][index]
    data = _scene_dict(f"{suite}/{index:03d}", orient, stacks, spec)
    if suite == "extra":  # the scene carries the types the default catalogue does not know
        new_types = extra_catalogue().types
        types = dict((*spec.movables, TRAY))
        used = sorted({types[o] for o in orient} & set(new_types))
        if used:
            data["types"] = {n: type_to_dict(new_types[n]) for n in used}
    return scene_from_dict(data, file=f"<suite {suite}>", catalogue=_catalogue())


def _check_suite(suite: str) -> None:
    if suite not in SUITES:
        raise UnknownNameError("suite", suite, SUITES)


def suite_scenes(suite: str) -> tuple[Scene, ...]:
    """All scenes of a suite, in their stable order."""
    _check_suite(suite)
    return tuple(_scene(suite, i) for i in range(len(_kept(suite)[0])))


def suite_stats(suite: str) -> SuiteStats:
    _check_suite(suite)
    return _kept(suite)[1]


def all_scene_names(suite: str | None = None) -> list[str]:
    """Names of the scenes of one suite (default: all suites), without building them."""
    suites = SUITES if suite is None else (suite,)
    for name in suites:
        _check_suite(name)
    return [f"{name}/{i:03d}" for name in suites for i in range(len(_kept(name)[0]))]


def get_scene(name: str) -> Scene:
    """A suite scene by its stable name, e.g. ``pick-place/017`` (only that scene is built)."""
    suite, _, number = name.partition("/")
    if suite in SUITES and len(number) == 3 and number.isdigit():
        index = int(number)
        if index < len(_kept(suite)[0]):
            return _scene(suite, index)
    raise UnknownNameError("scene", name, all_scene_names())
