"""Drawing a goal for a scene: a template's sampler, then the language's check that every
object the goal names has an unambiguous description (`language.refer`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from utamp_gym.scene.model import Scene
from utamp_gym.tasks.goal import Goal, split_literal
from utamp_gym.tasks.language import AmbiguousReference, instruction
from utamp_gym.tasks.templates import compose, make_goal, stand, template, up

#: draws of a template's parameters before a scene is declared to have none for it
DRAWS = 8


def _nameable(scene: Scene, goal: Goal) -> bool:
    try:
        instruction(scene, goal)
    except AmbiguousReference:
        return False
    return True


def sample_goal(scene: Scene, template_id: str, rng: Any) -> Goal | None:
    """A goal of template `template_id` (a composition ``a+b`` draws each part; parts that
    make the same literal twice or name the same object twice are drawn again) whose
    literals do not contradict one another (`contradiction`) and whose instruction is
    unambiguous, or None after `DRAWS` draws."""
    names = template_id.split("+")
    for _ in range(DRAWS):
        drawn = [template(n).sample(scene, rng) for n in names]
        if any(p is None for p in drawn):
            continue
        if len(names) == 1:
            goal = make_goal(scene, template_id, drawn[0])  # type: ignore[arg-type]
        else:
            if _overlap([p for p in drawn if p is not None]):
                continue
            goal = compose(scene, list(zip(names, drawn, strict=True)))  # type: ignore[arg-type]
        if contradiction(scene, goal.literals) is None and _nameable(scene, goal):
            return goal
    return None


def _overlap(params: Sequence[dict[str, Any]]) -> bool:
    """Whether two parts name a common object (their goals would interfere)."""
    seen: set[str] = set()
    for p in params:
        mine: set[str] = set()
        for k, v in p.items():
            if k == "region" or k.startswith("category"):
                continue
            mine |= set(v) if isinstance(v, (list, tuple)) else {str(v)}
        if mine & seen:
            return True
        seen |= mine
    return False


def contradiction(scene: Scene, literals: Sequence[str]) -> str | None:
    """Why `literals` cannot hold together in `scene` (None: no contradiction found).

    ``(oc PART A B)`` says PART of A touches B, so (PART, A) has one occupant, and a
    relation between two things holds from both sides: X standing on Y is also Y's upper
    part carrying X, X in a slot's region is also X standing on the slot. The positive
    atoms and these counterparts are checked for two occupants of one part (two objects in
    one region, an object on two supports, a cleared surface carrying something), for an
    atom and its negation, and for a cycle of objects standing on one another."""
    slots = {s.name for s in scene.slots}
    objects = set(scene.object_names)
    pos: set[tuple[str, ...]] = set()
    neg: set[tuple[str, ...]] = set()
    for lit in literals:
        positive, body = split_literal(lit)
        args = tuple(body[1:-1].split())
        (pos if positive else neg).add(args)
    derived = set(pos)
    on_graph: dict[str, str] = {}
    for a in pos:
        if a[0] != "oc" or len(a) != 4 or a[3] == "air":
            continue
        _, part, x, y = a
        if x in objects and part == stand(scene, x) and (y in objects or y in slots):
            derived.add(("oc", up(scene, y), y, x))
            if y in objects:
                on_graph[x] = y
        elif x in slots and part == "on" and y in objects:
            derived.add(("oc", stand(scene, y), y, x))
    occupant: dict[tuple[str, ...], str] = {}
    for a in sorted(derived):
        if a in neg:
            return f"{_pddl(a)} and its negation"
        if a[0] == "oc" and len(a) == 4:
            key = a[:3]
            if occupant.setdefault(key, a[3]) != a[3]:
                return f"{_pddl(key)} holds both {occupant[key]} and {a[3]}"
    for start in on_graph:
        seen, x = {start}, start
        while x in on_graph:
            x = on_graph[x]
            if x in seen:
                return f"a cycle of objects standing on one another through {x}"
            seen.add(x)
    return None


def _pddl(args: Sequence[str]) -> str:
    return "(" + " ".join(args) + ")"


__all__ = ["DRAWS", "contradiction", "sample_goal"]
