"""Physics grounding of the kitchen envs: execute a macro action, inject faults, perceive.

Why a layer of its own: the env never assumes an effect happened. After `reset` and after
every executed macro action (success or failure) the symbolic state is *perceived* from the
simulator (`utamp_gym.perception.abstraction.perceive` on the backend's `physical_state()`), and
`unexpected_atoms` compares it with what the action was predicted to do (execution
monitoring). With ``disturbance`` p > 0, each executed macro action is followed, with
probability p drawn from the env's generator, by one fault of `utamp_gym.backend.FAULT_KINDS`.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from utamp_gym.backend import Disturbable, Fault, MacroResult, PhysicsBackend
from utamp_gym.env.task import TOWER, progress
from utamp_gym.perception.abstraction import Perception, perceive
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.state import SymbolicState
from utamp_gym.symbolic.universe import Universe, UniverseByKey
from utamp_gym.tasks.goal import Goal
from utamp_gym.tasks.success import check_perception, literals_held

#: the second stream of an episode's world seed: its injected faults
FAULT_STREAM = 0xFA17
#: static predicates whose atoms perception re-derives (they follow the object's orientation)
ORIENTATION_PREFIXES = ("(force ", "(base ")


@dataclass(frozen=True)
class Executed:
    """One executed macro action: the backend's result, the injected fault, what was perceived."""

    macro: MacroResult
    fault: Fault | None
    perception: Perception
    perceive_s: float  # wall time of reading the physical state and abstracting it


@dataclass(frozen=True)
class Stepped:
    """One step the mask allowed: why it failed (None: it did not), the executed macro action
    (None: nothing reached a simulator), unexpected atoms and timings (s)."""

    failure: str | None
    executed: Executed | None = None
    unexpected: tuple[str, ...] = ()
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def macro(self) -> MacroResult | None:
        """The executed macro action's result (None: nothing was executed)."""
        return None if self.executed is None else self.executed.macro

    @property
    def fault(self) -> str | None:
        """The injected fault after it, as text (None: none)."""
        executed = self.executed
        return None if executed is None or executed.fault is None else str(executed.fault)


#: the step result of an action that did not fail and reached no simulator (shared: never
#: changed): an applied symbolic action, or nothing run (reset, a masked-out action)
NOT_RUN = Stepped(None)


def perceived_static(declared: frozenset[str], perception: Perception) -> frozenset[str]:
    """The episode's static atoms with the orientation atoms replaced by the perceived ones."""
    kept = frozenset(a for a in declared if not a.startswith(ORIENTATION_PREFIXES))
    return kept | perception.orientation


def unexpected_atoms(predicted: Iterable[str], perceived: Iterable[str]) -> list[str]:
    """Sorted ``"+ATOM"`` (perceived, not predicted) and ``"-ATOM"`` (predicted, not perceived)."""
    predicted, perceived = set(predicted), set(perceived)
    return sorted(
        [f"+{a}" for a in perceived - predicted] + [f"-{a}" for a in predicted - perceived]
    )


class PhysicalGrounding(UniverseByKey):
    """A physics backend plus perception and fault injection (see the module docstring): the
    env's grounding in physics (`utamp_gym.env.grounding.Grounding`); `state` is the env's
    symbolic state, which becomes the perceived one after every reset and executed step."""

    def __init__(
        self,
        backend: PhysicsBackend,
        universe: Universe,
        state: SymbolicState,
        objects: Sequence[str],
        disturbance: float = 0.0,
        record_timings: bool = False,
    ) -> None:
        if disturbance > 0 and not isinstance(backend, Disturbable):
            raise ValueError(
                f"disturbance={disturbance} needs a backend that can inject faults "
                f"(a disturb(rng) method); {type(backend).__name__} has none"
            )
        self.backend, self.disturbance = backend, disturbance
        self.simulator = backend
        self.universe, self.state, self.recorded = universe, state, record_timings
        self._rows = {n: i for i, n in enumerate(objects)}
        self._scene: Scene | None = None
        self._declared: frozenset[str] = frozenset()
        self._faults = None
        self.perception: Perception | None = None

    def reset(
        self,
        scene: Scene,
        declared: frozenset[str],
        np_random: np.random.Generator,
        world_seed: int | None = None,
    ) -> None:
        """Reset the simulator to `scene` and perceive its state; `declared`: the episode's
        static atoms. The simulator's generator is seeded with `world_seed`, and faults are
        drawn from its second stream (`FAULT_STREAM`); without it, the generator's seed and
        the faults are drawn from the env's `np_random`."""
        if world_seed is None:
            rng = np.random.default_rng(np_random.integers(2**63))
            self._faults: np.random.Generator | None = None
        else:
            rng = np.random.default_rng(world_seed)
            self._faults = np.random.default_rng([world_seed, FAULT_STREAM])
        self.backend.reset(scene, rng)
        self._scene, self._declared = scene, declared
        self._observe(self._perceive()[0])

    def step(self, a: int, np_random: np.random.Generator) -> Stepped:
        """Run action `a` the mask allows, maybe inject a fault, perceive, compare."""
        start = time.perf_counter()
        action = self.universe.actions[a]
        predicted = self._predicted(a)
        executed = self.execute(action, np_random if self._faults is None else self._faults)
        self._observe(executed.perception)
        unexpected = unexpected_atoms(predicted, executed.perception.atoms)
        macro = executed.macro
        timings: dict[str, float] = {}
        if self.recorded:
            timings = {
                **macro.timings,
                "perceive_s": executed.perceive_s,
                "step_s": time.perf_counter() - start,
            }
        else:  # wall-clock times would make info trajectories differ between runs
            executed = replace(executed, macro=replace(macro, timings={}))
        failure = None if macro.success else (macro.reason or f"{action} failed in simulation")
        return Stepped(failure, executed, tuple(unexpected), timings)

    def execute(self, action: str, rng: np.random.Generator) -> Executed:
        """Run `action`, maybe inject a fault (drawn from `rng`), then perceive."""
        macro = self.backend.execute(action)
        fault = None
        if self.disturbance > 0 and rng.random() < self.disturbance:
            assert isinstance(self.backend, Disturbable)
            fault = self.backend.disturb(rng)
        perception, seconds = self._perceive()
        return Executed(macro, fault, perception, seconds)

    def progress(self, goal: Goal, base: str, need_progress: bool) -> tuple[bool, int]:
        """(`goal` reached in the measured state: its literals hold in the perceived atoms and
        every object it is about is perceived, `utamp_gym.tasks.success`; reward shaping's
        progress in the perceived atoms, `utamp_gym.env.task.progress`, 0 unless asked)."""
        p = self.perception
        assert p is not None and self._scene is not None
        reached = check_perception(self._scene, goal, p).reached
        if not need_progress:
            return reached, 0
        height = len(p.tower(base)) if goal.template == TOWER else 0
        return reached, progress(goal, literals_held(goal, p.atoms), height)

    def pose_rows(self) -> np.ndarray:
        poses = np.zeros((len(self._rows), 7), np.float32)
        for name, pose in self.backend.object_poses().items():
            poses[self._rows[name]] = pose
        return poses

    def robot(self) -> np.ndarray:
        return np.asarray(self.backend.joint_positions(), np.float32).copy()

    def image(self, size: tuple[int, int]) -> np.ndarray:
        return np.asarray(self.backend.render(size[1], size[0]), np.uint8)

    frame = image  # render() shows the camera

    def draw(self, axes: Any) -> None:
        raise RuntimeError("physics grounding draws no schematic (its window is MuJoCo's)")

    def close(self) -> None:
        self.backend.close()

    def _observe(self, perception: Perception) -> None:
        """The env's symbolic state becomes the perceived one."""
        self.state.observe(perception.fluent, perceived_static(self._declared, perception))

    def _predicted(self, a: int) -> frozenset[str]:
        """Atoms action `a` is predicted to yield: its successor; atoms outside the universe
        and orientation atoms unchanged."""
        assert self.perception is not None
        fluent = self.universe.atoms_of(self.universe.successor(self.state.bits, a))
        return frozenset((*fluent, *self.state.unrepresented)) | self.perception.orientation

    def _perceive(self) -> tuple[Perception, float]:
        assert self._scene is not None
        start = time.perf_counter()
        self.perception = perceive(self._scene, self.backend.physical_state())
        return self.perception, time.perf_counter() - start
