"""The goal of each episode and its instruction: the env option ``task``.

Why a module: the symbolic state (termination), physics success, the planner policy, the
info and the observation all read one goal per scene, resolved here once and cached.

``task`` is

* None (default): the scene's own goal (a scene file's ``[goal]``, the procedural-v2
  splits), else the paper's tower on `Scene.tower_base` (every other suite: their results
  are unchanged);
* a template id or a composition (``"put-on"``, ``"put-on+clear"``,
  `utamp_gym.tasks.templates.TEMPLATES`): the scene's own goal if it has that template,
  ``"tower"`` the paper's tower, else a goal drawn once per scene by the template's sampler
  (`utamp_gym.tasks.sampling.sample_goal`) from a generator seeded with the SHA-256 of
  ``"<scene name>|<task>"``, so every process gets the same goal for a scene;
* a `Goal`: a templated goal is rebuilt in each scene from its template and parameters (its
  literals depend on how the objects stand); a custom one (literals only) is used as is.

Scenes where the task has no goal (no parameters fit, or the goal names an object the scene
lacks) are left out of the env's episodes (`usable`); an env none of whose scenes has one is
an error. The instruction is `utamp_gym.tasks.language.instruction` (seed 0); a custom goal,
which has no template, reads ``"make these hold: LITERAL, ..."``.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence

import numpy as np

from utamp_gym.errors import UtampError
from utamp_gym.scene.model import Scene
from utamp_gym.tasks.goal import CUSTOM, Goal
from utamp_gym.tasks.language import AmbiguousReference, instruction
from utamp_gym.tasks.sampling import sample_goal
from utamp_gym.tasks.templates import make_goal, parts, tower_goal

TOWER = "tower"
Task = str | Goal | None


def check_task(task: object) -> Task:
    """The ``task`` option, validated: None, a `Goal`, or a template id / composition
    (unknown names raise `UnknownNameError` listing the templates)."""
    if task is None or isinstance(task, Goal):
        return task
    if not isinstance(task, str):
        raise ValueError(f"task must be a goal template id or a Goal, got {task!r}")
    parts(task)
    return task


def _seed(scene: Scene, task: str) -> np.random.Generator:
    digest = hashlib.sha256(f"{scene.name}|{task}".encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def resolve_goal(scene: Scene, task: Task) -> Goal | None:
    """The goal of `task` in `scene` (module docstring); None if it has none there."""
    if task is None:
        return scene.goal if scene.goal is not None else tower_goal(scene)
    if isinstance(task, Goal):
        if task.template == CUSTOM:
            return task
        try:
            return make_goal(scene, task.template, task.param_dict)
        except (UtampError, ValueError):
            return None
    if scene.goal is not None and scene.goal.template == task:
        return scene.goal
    if task == TOWER:
        return tower_goal(scene)
    return sample_goal(scene, task, _seed(scene, task))


def goal_instruction(scene: Scene, goal: Goal) -> str:
    """The goal's instruction in `scene` (module docstring)."""
    if goal.template != CUSTOM:
        try:
            return instruction(scene, goal)
        except AmbiguousReference:
            pass
    return "make these hold: " + ", ".join(goal.literals)


class EpisodeGoals:
    """The goals and instructions of an env's scenes under one ``task``, cached per scene."""

    def __init__(self, task: Task) -> None:
        self.task = task
        self._goals: dict[str, Goal | None] = {}
        self._texts: dict[str, str] = {}

    def usable(self, scenes: Sequence[Scene]) -> tuple[Scene, ...]:
        """The scenes the task has a goal in (all of them for the default task)."""
        if self.task is None:
            return tuple(scenes)
        kept = tuple(s for s in scenes if self.get(s) is not None)
        if not kept:
            what = self.task if isinstance(self.task, str) else f"goal {self.task.to_json()}"
            raise ValueError(f"task {what!r} has no goal in any of the env's {len(scenes)} scenes")
        return kept

    def get(self, scene: Scene) -> Goal | None:
        if scene.key not in self._goals:
            self._goals[scene.key] = resolve_goal(scene, self.task)
        return self._goals[scene.key]

    def goal(self, scene: Scene) -> Goal:
        goal = self.get(scene)
        if goal is None:
            raise ValueError(f"task {self.task!r} has no goal in scene {scene.name}")
        return goal

    def override(self, scene: Scene) -> Goal | None:
        """The goal the symbolic state gets (None: the scene's own, else the tower)."""
        return None if self.task is None else self.goal(scene)

    def instruction(self, scene: Scene) -> str:
        if scene.key not in self._texts:
            self._texts[scene.key] = goal_instruction(scene, self.goal(scene))
        return self._texts[scene.key]


__all__ = ["TOWER", "EpisodeGoals", "Task", "check_task", "goal_instruction", "resolve_goal"]
