"""`SymbolicBackend`: symbolic grounding as a backend of the kitchen envs.

Why a backend: the env asks a grounding the same questions in both groundings (reset to a
scene, execute a macro action, the object poses, the robot's joints, the tower, a picture),
so it has no branch on the grounding. This backend answers them without a simulator: the
outcome model (`utamp_gym.env.outcome`, with ``masks`` geometric / none: the ground-truth
U-TAMP-2 precondition) decides whether an action the mask allows succeeds, a successful
action's effect is applied to the episode's symbolic state (`utamp_gym.env.state`), the poses
follow the documented rules of `utamp_gym.env.poses`, the robot stays at home, and pictures
are the top-down schematic (`utamp_gym.env.render`). It implements the `PhysicsBackend`
calls (`utamp_gym.backend`) except `physical_state` (nothing is simulated, nothing is
perceived: the symbolic state is the truth), and `Surveying`: the cameras' look
(``utamp2-perceived``) renders the episode's initial world through the MuJoCo backend, reset
with the episode's world seed (``reset(options={"world_seed": s})``), so it sees the poses and
colours the physics env of that seed starts from; MuJoCo is loaded only for a look.

The symbolic backend's views always show that initial arrangement, also after the episode
has acted: nothing is simulated, and what a look perceives (the objects' attributes) does not
change as they move, so a later look (interactive perception's extra looks) perceives the same
attributes. Only a backend without the episode's world (reset without a world seed) cannot
look: `NoWorldToLook`.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import numpy as np

from utamp_gym.backend import DEFAULT_BACKEND, MacroResult, PhysicsBackend, backend_factory
from utamp_gym.contract.views import ViewBundle
from utamp_gym.env.render import LabelledSchematic, SchematicRenderer
from utamp_gym.env.task import home_joints
from utamp_gym.errors import UtampError
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.outcome import OutcomeModel
from utamp_gym.symbolic.poses import SymbolicPoses
from utamp_gym.symbolic.state import SymbolicState
from utamp_gym.symbolic.universe import Universe, UniverseByKey


class NoWorldToLook(UtampError, RuntimeError):
    """A look in symbolic grounding without the episode's world seed."""


class SymbolicBackend(UniverseByKey):
    """The outcome model, the rule-moved poses and the schematic of one env's episodes.

    `state` is the env's symbolic state, advanced here by every successful action.
    """

    def __init__(
        self, universe: Universe, state: SymbolicState, objects: Sequence[str], masks: str
    ) -> None:
        self.universe, self.state = universe, state
        # masks geometric/none: the outcome model decides the steps the mask allows
        self.outcome = OutcomeModel(universe) if masks != "affordances" else None
        self.poses = SymbolicPoses(objects)
        self.renderer = SchematicRenderer(objects)
        self.labels = LabelledSchematic(objects)
        self.held: str | None = None
        self._home = home_joints()
        self._scene: Scene | None = None
        self._world: np.random.Generator | None = None  # the world's generator, undrawn
        self._simulator: PhysicsBackend | None = None  # made for the first look
        self._shown: tuple[str, Any] | None = None  # the world it is reset to

    # ------------------------------------------------------------------ PhysicsBackend
    def reset(self, scene: Scene, rng: np.random.Generator | None = None) -> None:
        """Start an episode in `scene` (nothing is random: `rng` is not drawn from; a copy
        of it seeds the world a look renders, `survey`)."""
        self._scene, self.held = scene, None
        self._world = None if rng is None else copy.deepcopy(rng)
        self.poses.reset(scene)
        if self.outcome is not None:
            self.outcome.reset(scene)
        self.renderer.reset(scene)
        self.labels.reset(scene)

    def execute(self, action: str) -> MacroResult:
        """Run the ground action `action` (PDDL string) on the symbolic state."""
        failure = self.execute_id(self.universe.index(action))
        return MacroResult(failure is None, failure)

    def execute_id(self, a: int) -> str | None:
        """Run universe action `a`; why it failed (None: applied)."""
        failure = None if self.outcome is None else self.outcome.failure(self.state, a)
        if failure is None:
            self.state.apply(a)
            kind, obj, target = self.universe.roles[a]
            self.poses.apply(kind, obj, target)
            if kind == "pick-support":
                self.held = obj
            elif kind == "place-support":
                self.held = None
        return failure

    def physical_state(self) -> Any:
        raise NotImplementedError("symbolic grounding simulates nothing: no physical state")

    def object_poses(self) -> dict[str, np.ndarray]:
        """Object name -> ``[x, y, z, qw, qx, qy, qz]`` (the scene's objects only)."""
        poses, present = self.poses.observation(), self.poses.present()
        return {n: poses[i] for i, n in enumerate(self.poses.names) if present[i]}

    def joint_positions(self) -> np.ndarray:
        """The Panda's ready pose with the fingers open (the robot never moves)."""
        return self._home.copy()

    def stacked_on_tray(self) -> list[str]:
        """The tower on the scene's base, bottom to top."""
        assert self._scene is not None, "reset() first"
        return self.poses.tower(self._scene.tower_base)

    def render(self, width: int, height: int) -> np.ndarray:
        """The unlabelled top-down schematic (what ``camera=True`` observes)."""
        poses, present = self.poses.observation(), self.poses.present()
        return self.renderer.render(poses, present, self.held, (height, width))

    def close(self) -> None:
        """Release the simulator a look was rendered with, if any."""
        if self._simulator is not None:
            self._simulator.close()
            self._simulator = self._shown = None

    # ------------------------------------------------------------------ Surveying
    def survey(self) -> ViewBundle:
        """The cameras' look at the episode's initial world (module docstring: also after
        the episode acted)."""
        return self._looking().survey()  # type: ignore[attr-defined, no-any-return]

    @property
    def cameras(self) -> Any:
        """The cameras of the world a look renders (`survey`)."""
        return self._looking().cameras  # type: ignore[attr-defined]

    def _looking(self) -> PhysicsBackend:
        """The MuJoCo backend reset to the episode's initial world (it is never stepped)."""
        if self._scene is None or self._world is None:
            raise NoWorldToLook(
                "a look in symbolic grounding renders the episode's world: reset the env "
                "with options={'world_seed': SEED} first"
            )
        shown = (self._scene.key, self._world.bit_generator.state)
        if self._simulator is None:
            self._simulator = backend_factory(DEFAULT_BACKEND)()
        if self._shown != shown:
            self._simulator.reset(self._scene, copy.deepcopy(self._world))
            self._shown = shown
        return self._simulator

    # ------------------------------------------------------------------ schematic views
    def labelled(self, size: tuple[int, int]) -> np.ndarray:
        """The labelled schematic, (height, width) `size` (what ``render()`` shows)."""
        poses, present = self.poses.observation(), self.poses.present()
        return self.labels.render(poses, present, self.held, size)

    def draw(self, axes: Any) -> None:
        """The labelled schematic into matplotlib axes (the human window)."""
        self.labels.draw(axes, self.poses.observation(), self.poses.present(), self.held)
