"""Drawing a goal for a scene: a template's sampler, then the language's check that every
object the goal names has an unambiguous description (`language.refer`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from utamp_gym.scene.model import Scene
from utamp_gym.tasks.goal import Goal
from utamp_gym.tasks.language import AmbiguousReference, instruction
from utamp_gym.tasks.templates import compose, make_goal, template

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
    instruction is unambiguous, or None after `DRAWS` draws."""
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
        if _nameable(scene, goal):
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


__all__ = ["DRAWS", "sample_goal"]
