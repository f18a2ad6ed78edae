"""The goal templates of kitchen organisation, each defined once: its parameters, the
literals they stand for in a scene (`literals`), a sampler of parameters from a scene and an
rng (`sample`), and its phrasings (`utamp_gym.tasks.language` fills them in).

Literals use the domains' predicates only (`utamp_gym.tasks.goal`). Where a template allows
several final arrangements (a stack in any order, an object anywhere on the table) its
literals say only what every such arrangement shares, so a planner or policy may reach any:

* "X stands on one of the supports T" is: the hand is empty (so X stands somewhere) and X
  stands on no other object or slot, ``(not (oc STAND X Z))`` for every Z outside T;
* "the objects S form one stack on B, in any order": each X in S stands on one of
  S + {B} minus X. Following the supports down from any X stays in S until it reaches B
  (stacks have no cycles), so all of S stands above B, one on another;
* "X stands on the table": X stands on no object.

``restack`` alone fixes an order: each of its objects on the one before, the first on the
base.

STAND is the part X stands on in its (fixed) orientation (`scene.model.STANDING_PART`).
A composition of templates (`compose`) is the conjunction of its parts' literals, its
parameters prefixed ``1.``, ``2.``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

from utamp_gym.errors import SceneError, UnknownNameError
from utamp_gym.scene.model import STANDING_PART, UP_PART, Scene
from utamp_gym.tasks.attributes import CATEGORIES, category
from utamp_gym.tasks.goal import HAND_EMPTY, Goal, atom, negated

Params = dict[str, Any]
Sampler = Callable[[Scene, Any], Params | None]


def stand(scene: Scene, obj: str) -> str:
    return STANDING_PART[scene.object(obj).orientation]


def up(scene: Scene, support: str) -> str:
    """The part of `support` (object or slot) that carries what stands on it."""
    if support in {s.name for s in scene.slots}:
        return "on"
    return UP_PART[scene.object(support).orientation]


def on(scene: Scene, obj: str, support: str) -> str:
    """``obj`` stands directly on ``support``."""
    return atom("oc", stand(scene, obj), obj, support)


def stands_among(scene: Scene, obj: str, supports: Sequence[str]) -> list[str]:
    """`obj` stands on none of the scene's objects and slots outside `supports`."""
    others = [*scene.object_names, *(s.name for s in scene.slots)]
    return [negated(on(scene, obj, z)) for z in others if z != obj and z not in supports]


def stack_on(scene: Scene, base: str, objects: Sequence[str]) -> list[str]:
    """`objects` form one stack on `base`, in any order (the module docstring)."""
    out: list[str] = []
    for x in objects:
        out += stands_among(scene, x, [base, *objects])
    return out


def on_table(scene: Scene, obj: str) -> list[str]:
    return stands_among(scene, obj, [s.name for s in scene.slots])


# ------------------------------------------------------------------ literals per template
def _tower(scene: Scene, p: Params) -> list[str]:
    """The paper's: every slot but the base's clear (`symbolic.problem.goal_atoms`)."""
    base_slot = scene.slot_of(p["base"])
    return [atom("oc", "on", s.name, "air") for s in scene.slots if s.name != base_slot]


def _subset_on(scene: Scene, p: Params) -> list[str]:
    return stack_on(scene, p["base"], p["objects"])


def _two_stacks(scene: Scene, p: Params) -> list[str]:
    return stack_on(scene, p["base"], p["objects"]) + stack_on(scene, p["base2"], p["objects2"])


def _put_on(scene: Scene, p: Params) -> list[str]:
    return [on(scene, p["object"], p["target"])]


def _clear(scene: Scene, p: Params) -> list[str]:
    return [atom("oc", up(scene, p["surface"]), p["surface"], "air")]


def _in_region(scene: Scene, p: Params) -> list[str]:
    return [atom("oc", "on", p["region"], p["object"])]


def _restack(scene: Scene, p: Params) -> list[str]:
    """`objects` in one stack on `base` in the given order, bottom first."""
    below = [p["base"], *p["objects"][:-1]]
    return [on(scene, x, b) for x, b in zip(p["objects"], below, strict=True)]


def _unstack(scene: Scene, p: Params) -> list[str]:
    out: list[str] = []
    for x in p["objects"]:
        out += on_table(scene, x)
    return out


def sort_groups(scene: Scene, p: Params) -> list[tuple[str, tuple[str, ...]]]:
    """(base, objects of its category) of a sort goal's one or two groups; the bases and
    the objects of no group stay out."""
    bases = [p["base"], *([p["base2"]] if "base2" in p else [])]
    values = [p["category"], *([p["category2"]] if "category2" in p else [])]
    return [
        (b, tuple(o for o in scene.object_names if o not in bases and category(scene, o) == v))
        for b, v in zip(bases, values, strict=True)
    ]


def _sort(scene: Scene, p: Params) -> list[str]:
    out: list[str] = []
    for base, objects in sort_groups(scene, p):
        out += stack_on(scene, base, objects)
    return out


# ------------------------------------------------------------------ samplers
def _pick(rng: Any, seq: Sequence[str]) -> str:
    return str(seq[int(rng.integers(len(seq)))])


def _subset(rng: Any, seq: Sequence[str], lo: int, hi: int) -> list[str]:
    k = int(rng.integers(lo, min(hi, len(seq)) + 1))
    return [str(seq[int(i)]) for i in sorted(rng.permutation(len(seq))[:k])]


def _bottoms(scene: Scene) -> list[str]:
    return [chain[0] for chain in scene.stacks.values()]


def _above(scene: Scene, obj: str) -> list[str]:
    chain = scene.stacks[scene.slot_of(obj)]
    return list(chain[chain.index(obj) + 1 :])


def _movable(scene: Scene, but: Sequence[str] = ()) -> list[str]:
    """Objects a goal may move: all but the scene's tower base (`goal_base`) and `but`."""
    return [o for o in scene.object_names if o != scene.goal_base and o not in but]


def _s_tower(scene: Scene, rng: Any) -> Params | None:
    try:
        return {"base": scene.tower_base}
    except SceneError:  # no declared base and not one tray
        return {"base": _pick(rng, _bottoms(scene))}


def _s_subset_on(scene: Scene, rng: Any) -> Params | None:
    base = _pick(rng, _bottoms(scene))
    rest = _movable(scene, [base])
    if len(rest) < 3:  # all of them would be the tower
        return None
    objects = _subset(rng, rest, 2, len(rest) - 1)
    return {"base": base, "objects": objects}


def _s_two_stacks(scene: Scene, rng: Any) -> Params | None:
    bottoms = _bottoms(scene)
    if len(bottoms) < 2 or scene.n_objects < 4:
        return None
    b1, b2 = (str(bottoms[int(i)]) for i in rng.permutation(len(bottoms))[:2])
    rest = _movable(scene, [b1, b2])
    if len(rest) < 2:
        return None
    order = [rest[int(i)] for i in rng.permutation(len(rest))]
    k = int(rng.integers(1, len(order)))
    return {"base": b1, "objects": sorted(order[:k]), "base2": b2, "objects2": sorted(order[k:])}


def _s_put_on(scene: Scene, rng: Any) -> Params | None:
    x = _pick(rng, _movable(scene))
    targets = [o for o in scene.object_names if o not in (x, scene.support_of(x))]
    return {"object": x, "target": _pick(rng, targets)} if targets else None


def _s_clear(scene: Scene, rng: Any) -> Params | None:
    loaded = [o for o in scene.object_names if _above(scene, o)]
    return {"surface": _pick(rng, loaded)} if loaded else None


def _s_in_region(scene: Scene, rng: Any) -> Params | None:
    x = _pick(rng, _movable(scene))
    regions = [s.name for s in scene.slots if scene.support_of(x) != s.name]
    return {"object": x, "region": _pick(rng, regions)}


def _s_unstack(scene: Scene, rng: Any) -> Params | None:
    towers = [b for b in _bottoms(scene) if len(_above(scene, b)) >= 2]
    if not towers:
        return None
    base = _pick(rng, towers)
    return {"base": base, "objects": _above(scene, base)}


def _s_restack(scene: Scene, rng: Any) -> Params | None:
    """Every object but the tower's base (at least three) in one stack on it in a drawn
    order that turns over a pair standing one on another now, when the scene has one (so
    the pair is taken apart first, with temporary placements)."""
    tower = _s_tower(scene, rng)
    if tower is None:
        return None
    base = tower["base"]
    rest = _movable(scene, [base])
    if len(rest) < 3:
        return None
    pairs = [(x, scene.support_of(x)) for x in rest if scene.support_of(x) in (*rest, base)]
    order = rest
    for _ in range(6):
        order = [rest[int(i)] for i in rng.permutation(len(rest))]
        chain = [base, *order]
        if not pairs or any(chain.index(x) < chain.index(y) for x, y in pairs):
            break
    return {"base": base, "objects": order}


def _s_sort(scene: Scene, rng: Any) -> Params | None:
    bottoms = _bottoms(scene)
    b = [str(bottoms[int(i)]) for i in rng.permutation(len(bottoms))[:2]]
    present = [c for c in CATEGORIES if any(category(scene, o) == c for o in scene.object_names
                                             if o not in b)]  # fmt: skip
    if not present:
        return None
    cats = [present[int(i)] for i in rng.permutation(len(present))[:2]]
    p: Params = {"base": b[0], "category": cats[0]}
    if len(b) == 2 and len(cats) == 2 and rng.random() < 0.5:
        p.update(base2=b[1], category2=cats[1])
    groups = sort_groups(scene, p)
    return p if all(objs for _, objs in groups) else None


class Template(NamedTuple):
    """A goal template: `build` makes its literals (the hand empty is added), `sample` draws
    parameters (None: the scene has none), `phrasings` are its instructions."""

    id: str
    params: tuple[str, ...]  # names; those in `lists` take lists of objects
    lists: tuple[str, ...]
    build: Callable[[Scene, Params], list[str]]
    sample: Sampler
    phrasings: tuple[str, ...]
    summary: str


TEMPLATES: dict[str, Template] = {
    t.id: t
    for t in (
        Template(
            "tower", ("base",), (), _tower, _s_tower,
            ("stack everything on {base}", "put all the objects in one tower on {base}",
             "build a single tower of every object on {base}"),
            "the paper's goal: every object in one tower on the base",
        ),
        Template(
            "subset-on", ("base", "objects"), ("objects",), _subset_on, _s_subset_on,
            ("stack {objects} on {base}", "put {objects} on {base}, in any order",
             "make one stack of {objects} on top of {base}"),
            "a named subset in one stack on a base, in any order",
        ),
        Template(
            "two-stacks", ("base", "objects", "base2", "objects2"), ("objects", "objects2"),
            _two_stacks, _s_two_stacks,
            ("stack {objects} on {base} and {objects2} on {base2}",
             "make two stacks: {objects} on {base}; {objects2} on {base2}"),
            "two stacks on two bases",
        ),
        Template(
            "put-on", ("object", "target"), (), _put_on, _s_put_on,
            ("put {object} on {target}", "place {object} on top of {target}",
             "set {object} down on {target}"),
            "one object directly on another",
        ),
        Template(
            "clear", ("surface",), (), _clear, _s_clear,
            ("clear {surface}", "take everything off {surface}", "leave {surface} empty"),
            "nothing left on a surface",
        ),
        Template(
            "in-region", ("object", "region"), (), _in_region, _s_in_region,
            ("move {object} to {region}", "put {object} down in {region}",
             "place {object} by itself in {region}"),
            "an object standing on the table in a region (slot)",
        ),
        Template(
            "unstack", ("base", "objects"), ("objects",), _unstack, _s_unstack,
            ("unstack the tower on {base} onto the table",
             "take the tower on {base} apart and put each piece on the table"),
            "every object above a base standing on the table",
        ),
        Template(
            "restack", ("base", "objects"), ("objects",), _restack, _s_restack,
            ("restack {objects} on {base}, bottom to top in this order",
             "build one stack on {base} of {objects}, in this order from the bottom up"),
            "every object but a base in one stack on it, in a given order",
        ),
        Template(
            "sort", ("base", "category", "base2", "category2"), (), _sort, _s_sort,
            ("put all the {category} on {base}", "sort the {category} onto {base}"),
            "every object of a category in one stack on a base (one or two groups)",
        ),
    )
}  # fmt: skip
#: sort's second group is optional
OPTIONAL = {"sort": ("base2", "category2")}
SORT_TWO = ("put all the {category} on {base} and all the {category2} on {base2}",
            "sort the {category} onto {base} and the {category2} onto {base2}")  # fmt: skip


def template(name: str) -> Template:
    try:
        return TEMPLATES[name]
    except KeyError:
        raise UnknownNameError("goal template", name, TEMPLATES) from None


def parts(template_id: str) -> list[str]:
    """The templates of a composition (``put-on+clear`` -> [put-on, clear]); one for a
    template."""
    names = template_id.split("+")
    for n in names:
        template(n)
    return names


def part_params(template_id: str, params: Mapping[str, Any]) -> list[Params]:
    """Each part's parameters: a composition's are prefixed ``1.``, ``2.``."""
    names = parts(template_id)
    if len(names) == 1:
        return [dict(params)]
    return [
        {k.split(".", 1)[1]: v for k, v in params.items() if k.startswith(f"{i}.")}
        for i in range(1, len(names) + 1)
    ]


def make_goal(scene: Scene, template_id: str, params: Mapping[str, Any]) -> Goal:
    """The goal of a template (or composition) with `params` in `scene`: its literals, the
    hand empty first. Unknown or missing parameters, or names the scene lacks, raise
    ValueError / UnknownNameError."""
    literals = [HAND_EMPTY]
    for name, p in zip(parts(template_id), part_params(template_id, params), strict=True):
        t = template(name)
        need = [k for k in t.params if k not in OPTIONAL.get(name, ())]
        missing = [k for k in need if k not in p]
        extra = [k for k in p if k not in t.params]
        if missing or extra:
            raise ValueError(
                f"goal template {name!r} takes {', '.join(t.params)}"
                + (f"; missing {', '.join(missing)}" if missing else "")
                + (f"; unknown {', '.join(extra)}" if extra else "")
            )
        _check_names(scene, name, p)
        literals += t.build(scene, p)
    return Goal.make(template_id, params, literals)


def _check_names(scene: Scene, name: str, p: Params) -> None:
    slots = [s.name for s in scene.slots]
    for k, v in p.items():
        values = v if isinstance(v, (list, tuple)) else [v]
        for x in values:
            if k.startswith("category"):
                valid: Sequence[str] = list(CATEGORIES)
            elif k == "region":
                valid = slots
            else:
                valid = scene.object_names
            if x not in valid:
                raise UnknownNameError(f"{name} goal's {k}", str(x), valid)


def tower_goal(scene: Scene) -> Goal:
    """The paper's goal for a scene: everything in one tower on `Scene.tower_base`."""
    return make_goal(scene, "tower", {"base": scene.tower_base})


def compose(scene: Scene, goals: Sequence[tuple[str, Mapping[str, Any]]]) -> Goal:
    """The conjunction of several templates' goals (``put-on+clear``)."""
    params = {f"{i}.{k}": v for i, (_, p) in enumerate(goals, start=1) for k, v in p.items()}
    return make_goal(scene, "+".join(n for n, _ in goals), params)


__all__ = [
    "OPTIONAL",
    "SORT_TWO",
    "TEMPLATES",
    "Template",
    "compose",
    "make_goal",
    "on",
    "on_table",
    "part_params",
    "parts",
    "sort_groups",
    "stack_on",
    "stand",
    "stands_among",
    "template",
    "tower_goal",
    "up",
]
