"""Physics success: a goal's literals holding in the *measured* state.

`goal_reached` asks `perception.abstraction.perceive` for the atoms of a physical state and
checks the goal's literals on them (`tasks.goal.unmet`). Negated literals alone would also
hold for an object that toppled or fell off the table (perception gives such an object no
atoms), so every object the goal names must have a symbol too: all objects for the tower
(the paper's goal names slots, not objects), the named ones for every other template.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import NamedTuple

from utamp_gym.contract.state import PhysicalState
from utamp_gym.perception.abstraction import Perception, perceive
from utamp_gym.scene.model import Scene
from utamp_gym.tasks.goal import CUSTOM, Goal, unmet
from utamp_gym.tasks.templates import part_params, parts, sort_groups


class GoalCheck(NamedTuple):
    """Whether the goal is reached; its unmet literals; goal objects without a symbol."""

    reached: bool
    unmet: tuple[str, ...]
    lost: dict[str, str]  # object -> why perception gives it no symbol


def goal_objects(scene: Scene, goal: Goal) -> tuple[str, ...]:
    """The objects a goal is about (every object for the tower and a custom goal)."""
    if goal.template == CUSTOM:
        return scene.object_names
    names: list[str] = []
    for name, p in zip(
        parts(goal.template), part_params(goal.template, goal.param_dict), strict=True
    ):
        if name == "tower":
            return scene.object_names
        if name == "sort":
            for base, objs in sort_groups(scene, p):
                names += [base, *objs]
            continue
        for k, v in p.items():
            if k != "region" and not k.startswith("category"):
                names += list(v) if isinstance(v, (list, tuple)) else [str(v)]
    return tuple(dict.fromkeys(names))


def check_perception(scene: Scene, goal: Goal, perception: Perception) -> GoalCheck:
    lost = {o: perception.anomalies[o] for o in goal_objects(scene, goal)
            if o in perception.anomalies}  # fmt: skip
    missing = unmet(goal, perception.atoms)
    return GoalCheck(not missing and not lost, missing, lost)


def literals_held(goal: Goal, atoms: Iterable[str]) -> int:
    """How many of the goal's literals hold in a state given by its true atoms."""
    return len(goal.literals) - len(unmet(goal, atoms))


def goal_reached(scene: Scene, goal: Goal, state: PhysicalState) -> GoalCheck:
    """The goal checked on the atoms perceived in a physical state."""
    return check_perception(scene, goal, perceive(scene, state))


__all__ = ["GoalCheck", "check_perception", "goal_objects", "goal_reached", "literals_held"]
