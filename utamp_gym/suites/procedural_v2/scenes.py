"""A procedural-v2 scene: the v1 generator's objects and layout (`spec.V2`), then a goal of
one of the split's templates. A pure function of (split, seed), like v1's.

The goal's template is drawn uniformly from `SPLIT_TEMPLATES` and its parameters by the
template's sampler (`tasks.sampling.sample_goal`), from a generator seeded by the SHA-256 of
("utamp-procedural-goal", v2, split, seed). Of `GOAL_DRAWS` draws the first that passes
quick checks on the rules' affordance facts under the split file's domain
(`spec.DOMAIN`) is kept (what it moves can be picked up; a stack's
objects can stand on one another in some order; an object can stand on its target), else
the first drawn: such goals are often unachievable, and the planner labels every goal
(`labels`). A goal that already holds in the scene is never kept.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import pairwise
from typing import NamedTuple

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.rules import derive_affordances
from utamp_gym.affordances.sources import EXTENDED_DOMAINS
from utamp_gym.kitchenware.params import rng_for
from utamp_gym.scene.model import UP_PART, Scene
from utamp_gym.suites.generate import _liftable_from_above, _supports, tower_achievable
from utamp_gym.suites.procedural.layout import generate_scene as _v1_style_scene
from utamp_gym.suites.procedural.objects import TABLE_TYPE, _catalogue, goal_achievable
from utamp_gym.suites.procedural.spec import NoLayout
from utamp_gym.suites.procedural_v2.spec import (
    DOMAIN,
    GOAL_DRAWS,
    MAX_GOAL_STACK,
    RESTACK_DRAWS,
    SPLIT_TEMPLATES,
    V2,
    VERSION,
    check_split,
)
from utamp_gym.symbolic.problem import scene_facts
from utamp_gym.tasks.goal import Goal, goal_holds
from utamp_gym.tasks.sampling import sample_goal
from utamp_gym.tasks.templates import part_params, parts, sort_groups

Kind = tuple[str, str]


class GoalScene(NamedTuple):
    """One generated v2 scene (its goal in `scene.goal`) and what it was made of."""

    scene: Scene
    seed: int
    families: tuple[str, ...]  # per object, scene order
    template: str


def generate_scene(split: str, seed: int, index: int = 0) -> GoalScene:
    """The scene of `seed` in `split`, named as its `index`-th (`NoLayout` if the seed has
    no valid layout or no goal of its template)."""
    g = _v1_style_scene(check_split(split), seed, index, V2)
    scene = g.scene
    rng = rng_for("utamp-procedural-goal", VERSION, split, seed)
    options = SPLIT_TEMPLATES[split]
    template_id = options[int(rng.integers(len(options)))]
    facts = derive_affordances(
        [_catalogue()[TABLE_TYPE], *scene.custom_types.values()], DOMAIN in EXTENDED_DOMAINS
    )  # the final (calibrated) rules, the ones the labeller plans with
    initial = scene_facts(scene, (), DOMAIN)
    first: Goal | None = None
    for _ in range(RESTACK_DRAWS if template_id == "restack" else GOAL_DRAWS):
        goal = sample_goal(scene, template_id, rng)
        if goal is None or goal_height(scene, goal) > MAX_GOAL_STACK:
            continue
        if goal_holds(goal, initial):  # nothing to do: draw again
            continue
        first = first or goal
        if plausible(scene, goal, facts):
            first = goal
            break
    if first is None:
        raise NoLayout(f"no {template_id} goal in this scene")
    return GoalScene(scene._replace(goal=first), seed, g.families, template_id)


def plausible(scene: Scene, goal: Goal, facts: frozenset[Fact]) -> bool:
    """Quick necessary-looking checks of a goal on the type-level affordance facts (not a
    proof either way: the planner labels the goal)."""
    kinds: dict[str, Kind] = {o.name: (o.type, o.orientation) for o in scene.objects}
    lift = {o: _liftable_from_above(facts, t, UP_PART[ori]) for o, (t, ori) in kinds.items()}

    def free(objs: Sequence[str]) -> bool:
        """They and everything on them can be picked up."""
        return all(lift[x] and all(lift[a] for a in _above(scene, x)) for x in objs)

    def stack(base: str, objs: Sequence[str]) -> bool:
        return free([*objs, *_above(scene, base)]) and tower_achievable(
            facts, kinds[base], [kinds[o] for o in objs]
        )

    for name, p in zip(parts(goal.template), part_params(goal.template, goal.param_dict),
                       strict=True):  # fmt: skip
        if name == "tower":
            order = sorted(scene.stacks.values(), key=lambda c: p["base"] not in c)
            ok = goal_achievable(facts, kinds, order)
        elif name == "restack":  # each object can stand on the one below it
            chain = [p["base"], *p["objects"]]
            ok = free([*p["objects"], *_above(scene, p["base"])]) and all(
                _supports(facts, kinds[b], kinds[x]) for b, x in pairwise(chain)
            )
        elif name in ("subset-on", "two-stacks"):
            ok = stack(p["base"], p["objects"]) and (
                "base2" not in p or stack(p["base2"], p["objects2"])
            )
        elif name == "sort":
            ok = all(stack(b, objs) for b, objs in sort_groups(scene, p))
        elif name == "put-on":
            ok = free([p["object"]]) and _supports(facts, kinds[p["target"]], kinds[p["object"]])
            ok = ok and free(_above(scene, p["target"]))
        elif name == "clear":
            ok = free(_above(scene, p["surface"]))
        elif name == "in-region":
            ok = free([p["object"]]) and _supports(facts, None, kinds[p["object"]])
        else:  # unstack
            ok = free(p["objects"]) and all(_supports(facts, None, kinds[o]) for o in p["objects"])
        if not ok:
            return False
    return True


def goal_height(scene: Scene, goal: Goal) -> float:
    """The height (m) of the tallest stack the goal asks for: all objects for the tower, a
    base's stack up to it with the objects put on it for the others (0 if it builds none)."""

    def h(objs: Sequence[str]) -> float:
        return sum(scene.type_of(o).bbox.max[2] - scene.type_of(o).bbox.min[2] for o in objs)

    def below(x: str) -> list[str]:
        chain = scene.stacks[scene.slot_of(x)]
        return list(chain[: chain.index(x) + 1])

    tallest = 0.0
    for name, p in zip(parts(goal.template), part_params(goal.template, goal.param_dict),
                       strict=True):  # fmt: skip
        if name == "tower":
            tallest = max(tallest, h(scene.object_names))
        elif name in ("subset-on", "two-stacks", "sort", "restack"):
            groups = (
                sort_groups(scene, p)
                if name == "sort"
                else [(p["base"], p["objects"])]
                + ([(p["base2"], p["objects2"])] if "base2" in p else [])
            )
            for base, objs in groups:
                tallest = max(tallest, h([*below(base), *objs]))
        elif name == "put-on":
            tallest = max(tallest, h([*below(p["target"]), p["object"]]))
    return float(tallest)


def _above(scene: Scene, obj: str) -> list[str]:
    chain = scene.stacks[scene.slot_of(obj)]
    return list(chain[chain.index(obj) + 1 :])
