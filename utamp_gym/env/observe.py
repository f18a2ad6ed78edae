"""What a kitchen env's agent observes: the observation space and each step's observation.

Why a module of its own: `UTampKitchenEnv` (`utamp_gym.env.kitchen`) is the loop; the
observation is assembled from several parts that only the interface and the options decide
(the grounded entries or the object slots, the goal entries, the camera image), the same in
both groundings, whose numbers come from the env's symbolic state and its grounding.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from gymnasium import spaces

from utamp_gym.env.object_goal import goal_entries, goal_entry_spaces
from utamp_gym.env.objects import ObjectInterface
from utamp_gym.env.task import observation_space
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.atoms import EpisodeAtoms
from utamp_gym.symbolic.scene_cache import SceneCache
from utamp_gym.symbolic.state import SymbolicState
from utamp_gym.symbolic.universe import Universe, UniverseByKey

if TYPE_CHECKING:
    from utamp_gym.env.grounding import Grounding
    from utamp_gym.env.options import EnvOptions

Obs = dict[str, np.ndarray]
#: fluent states whose ``symbolic`` vector an `Observer` keeps (then it starts afresh)
VECTORS_KEPT = 4096


class ScenePresence:
    """Which observation rows (`objects`) are objects of the episode's scene."""

    def __init__(self, objects: Sequence[str]) -> None:
        self._objects = tuple(objects)
        self._rows = np.zeros(len(self._objects), np.int8)
        self._cache: SceneCache[np.ndarray] = SceneCache()  # resets are frequent

    def reset(self, scene: Scene) -> None:
        self._rows = self._cache.get(scene.key, lambda: self._of(scene))

    def _of(self, scene: Scene) -> np.ndarray:
        names = set(scene.object_names)
        return np.array([n in names for n in self._objects], np.int8)

    def rows(self) -> np.ndarray:
        return self._rows.copy()  # the cached array itself is never handed out


def grounded_space(opts: EnvOptions, universe: Universe) -> spaces.Dict:
    """The grounded interface's observation space (`UTampKitchenEnv` documents it)."""
    image = opts.image_size if opts.camera else None
    return observation_space(len(universe.fluent_atoms), len(opts.objects), image)


class Observer(UniverseByKey):
    """The observation space of one env's options, and its observations (module docstring):
    `reset` at every episode start (after the object slots are drawn), then ``observer()``.

    The ``symbolic`` vector is a pure function of the symbolic state's bits, and episodes
    revisit states (an undone pick, the same tower built again): the vectors of the last
    `VECTORS_KEPT` states met are kept, and each observation gets a copy."""

    def __init__(
        self,
        opts: EnvOptions,
        universe: Universe,
        state: SymbolicState,
        grounding: Grounding,
        objects: ObjectInterface | None,
    ) -> None:
        self.universe, self._state, self._grounding, self._objects = (
            universe, state, grounding, objects,
        )  # fmt: skip
        self._rows = opts.objects
        self._present = ScenePresence(opts.objects)
        self._image_size = opts.image_size if opts.camera else None
        self._goal_observation = opts.goal_observation
        self._goal: dict[str, np.ndarray] = {}  # the episode's goal entries
        self._vectors: dict[int, np.ndarray] = {}  # state bits -> its symbolic vector
        space = grounded_space(opts, universe)
        if objects is not None:  # fixed spaces over object slots (env.objects)
            image = space.spaces.get("image")
            space = objects.observation_space
            if image is not None:
                space["image"] = image
        if opts.goal_observation:  # a new env id's spaces (env.object_goal)
            space.spaces.update(goal_entry_spaces(objects, universe))
        self.space = space
        self._plain = objects is None and not opts.goal_observation and not opts.camera

    def reset(self, scene: Scene, atoms: EpisodeAtoms) -> None:
        """Start an episode of `scene` whose initial atoms (and goal) are `atoms`."""
        self._present.reset(scene)
        if self._goal_observation:
            self._goal = goal_entries(self._objects, self.universe, atoms)

    def __call__(self) -> Obs:
        """The observation now (fresh arrays)."""
        state, grounding = self._state, self._grounding
        if self._plain:  # the grounded entries only: the common case, first
            return {
                "symbolic": self._vector(),
                "object_poses": grounding.pose_rows(),
                "present": self._present.rows(),
                "robot": grounding.robot(),
            }
        if self._objects is not None:
            rows = dict(zip(self._rows, grounding.pose_rows(), strict=True))
            obs = self._objects.observation(self._vector(), state.static_atoms, rows)
        else:
            obs = {
                "symbolic": self._vector(),
                "object_poses": grounding.pose_rows(),
                "present": self._present.rows(),
                "robot": grounding.robot(),
            }
        if self._goal:
            obs.update({k: v.copy() for k, v in self._goal.items()})
        if self._image_size is not None:
            obs["image"] = grounding.image(self._image_size)
        return obs

    def _vector(self) -> np.ndarray:
        """A fresh copy of the ``symbolic`` vector of the state now (class docstring)."""
        bits = self._state.bits
        vector = self._vectors.get(bits)
        if vector is None:
            if len(self._vectors) >= VECTORS_KEPT:
                self._vectors.clear()
            vector = self._vectors[bits] = self._state.vector()
        return vector.copy()
