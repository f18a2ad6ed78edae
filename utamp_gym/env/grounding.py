"""What the kitchen env asks of its grounding, and the symbolic one.

Why: `UTampKitchenEnv` is one loop for both groundings. It owns the symbolic state, the
masks, the task's reward and termination and the info; a `Grounding` owns the backend (the
MuJoCo simulator with perception and faults: `utamp_gym.env.physics.PhysicalGrounding`; or
`SymbolicBackend`: `SymbolicGrounding` here) and answers the same calls for both:

* `reset` / `step`: start an episode, run an action the mask allows (`Stepped`: its failure,
  what was executed, unexpected atoms, timings), keeping the env's symbolic state current;
* `progress`: goal reached (symbolic: its literals hold in the state; physics: in the
  measured state, `utamp_gym.tasks.success`) and reward shaping's progress towards it
  (`utamp_gym.env.task.progress`); `pose_rows` / `robot`: the observation's poses and
  joints; `image` (the camera observation), `frame` (what ``render()`` shows), `draw` (the
  labelled schematic for the symbolic human window);
* `backend`, `simulator` (the backend, if it simulates: what the viewers watch),
  `perception` (None when nothing is perceived), `recorded` (whether
  ``info["timings"]`` holds wall-clock times).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from utamp_gym.backend import DEFAULT_PERCEPTION, PhysicsBackend, backend_factory
from utamp_gym.env.physics import NOT_RUN, PhysicalGrounding, Stepped
from utamp_gym.env.symbolic_backend import SymbolicBackend
from utamp_gym.env.task import TOWER, progress
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.state import SymbolicState
from utamp_gym.symbolic.universe import Universe
from utamp_gym.tasks.goal import Goal

if TYPE_CHECKING:
    from utamp_gym.env.options import EnvOptions
    from utamp_gym.perception.abstraction import Perception


class Grounding(Protocol):
    """The calls the env makes on its grounding (module docstring)."""

    backend: PhysicsBackend
    simulator: PhysicsBackend | None  # what a live viewer may watch (None: no simulator)
    recorded: bool

    @property
    def perception(self) -> Perception | None: ...

    def reset(
        self,
        scene: Scene,
        declared: frozenset[str],
        np_random: np.random.Generator,
        world_seed: int | None = None,
    ) -> None: ...

    def step(self, a: int, np_random: np.random.Generator) -> Stepped: ...

    def progress(self, goal: Goal, base: str, need_progress: bool) -> tuple[bool, int]: ...

    def pose_rows(self) -> np.ndarray: ...

    def robot(self) -> np.ndarray: ...

    def image(self, size: tuple[int, int]) -> np.ndarray: ...

    def frame(self, size: tuple[int, int]) -> np.ndarray: ...

    def draw(self, axes: Any) -> None: ...

    def close(self) -> None: ...


class SymbolicGrounding:
    """The env's grounding by `SymbolicBackend`: effects applied, nothing perceived."""

    recorded = False  # no wall-clock times: equal seeds give equal infos
    perception = None
    simulator = None

    def __init__(
        self, universe: Universe, state: SymbolicState, objects: Sequence[str], masks: str
    ) -> None:
        self.state = state
        self.backend = backend = SymbolicBackend(universe, state, objects, masks)
        # the backend's own calls, bound once (a symbolic step is a few microseconds)
        self.pose_rows = backend.poses.observation
        self.robot = backend.joint_positions
        self._execute = backend.execute_id

    def reset(
        self,
        scene: Scene,
        declared: frozenset[str],
        np_random: np.random.Generator,
        world_seed: int | None = None,
    ) -> None:
        """Start an episode (nothing is random: no generator is drawn from; `world_seed`
        seeds the world a look renders, `SymbolicBackend.survey`)."""
        self.backend.reset(scene, None if world_seed is None else np.random.default_rng(world_seed))

    def step(self, a: int, np_random: np.random.Generator) -> Stepped:
        failure = self._execute(a)
        return NOT_RUN if failure is None else Stepped(failure)

    def progress(self, goal: Goal, base: str, need_progress: bool) -> tuple[bool, int]:
        """(every goal literal holds in the symbolic state, which the state was given at
        reset; the shaping's progress, `utamp_gym.env.task.progress`, 0 unless asked)."""
        if not need_progress:
            return self.state.goal_reached(), 0
        height = len(self.backend.poses.tower(base)) if goal.template == TOWER else 0
        return self.state.goal_reached(), progress(goal, self.state.goal_literals_held(), height)

    def image(self, size: tuple[int, int]) -> np.ndarray:
        return self.backend.render(size[1], size[0])

    def frame(self, size: tuple[int, int]) -> np.ndarray:
        return self.backend.labelled(size)

    def draw(self, axes: Any) -> None:
        self.backend.draw(axes)

    def close(self) -> None:
        self.backend.close()


def make_grounding(opts: EnvOptions, universe: Universe, state: SymbolicState) -> Grounding:
    """The grounding the options ask for (``grounding``, ``backend``, ``perception``, ...)."""
    if opts.grounding == "symbolic":
        return SymbolicGrounding(universe, state, opts.objects, opts.masks)
    factory = backend_factory(opts.backend)
    extra = {} if opts.perception == DEFAULT_PERCEPTION else {"perception": opts.perception}
    backend = factory(pose_noise=opts.pose_noise, **extra, **opts.backend_kwargs)
    return PhysicalGrounding(
        backend, universe, state, opts.objects, opts.disturbance, opts.record_timings
    )
