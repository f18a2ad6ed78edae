"""One episode of a kitchen env: the scene and goal `reset` picks, fixed until the next reset.

Why a record: every step reads the episode's goal and tower base and repeats its scene name,
goal literals and instruction in the info. `Episode` holds them typed and computed once, so
the loop neither checks for a missing episode on every read nor derives them again.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from utamp_gym.env.goals import EpisodeGoals
from utamp_gym.env.info import EpisodeInfo
from utamp_gym.errors import UnknownNameError
from utamp_gym.scene.model import Scene
from utamp_gym.tasks.goal import Goal

#: what ``reset(options=...)`` accepts: the episode's scene, and the seed of its simulated
#: world (physics: the simulator's generator, and a second stream of it for injected
#: faults; default: drawn from the env's RNG, which then also draws the faults)
RESET_OPTIONS = ("scene", "world_seed")


def chosen_scene(
    scenes: Sequence[Scene], options: Mapping[str, Any] | None, np_random: np.random.Generator
) -> tuple[Scene, int | None]:
    """(the episode's scene, its world seed) from ``reset``'s `options`: the named scene of
    `scenes`, else one drawn uniformly from `np_random`; an unknown option or scene name
    raises `UnknownNameError` with the valid ones."""
    options = dict(options or {})
    name = options.pop("scene", None)
    world_seed = options.pop("world_seed", None)
    if options:
        raise UnknownNameError("reset option", next(iter(options)), RESET_OPTIONS)
    if name is None:
        return scenes[int(np_random.integers(len(scenes)))], world_seed
    by_name = {s.name: s for s in scenes}
    if name not in by_name:
        raise UnknownNameError("scene of this env", str(name), by_name)
    return by_name[name], world_seed


@dataclass(frozen=True, slots=True)
class Episode:
    """What one episode is about (module docstring); `info` makes its info dicts."""

    scene: Scene
    goal: Goal
    base: str  # the object the tower stands on (`Scene.tower_base`; reward shaping)
    instruction: str  # the goal in words
    info: EpisodeInfo

    @classmethod
    def start(cls, scene: Scene, goals: EpisodeGoals) -> Episode:
        """The episode of `scene` under the env's task (`goals`)."""
        goal, text = goals.goal(scene), goals.instruction(scene)
        info = EpisodeInfo(scene.name, scene.object_names, goal.literals, text)
        return cls(scene, goal, scene.tower_base, text, info)
