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
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from utamp_gym.backend import Disturbable, Fault, MacroResult, PhysicsBackend
from utamp_gym.perception.abstraction import Perception, perceive
from utamp_gym.scene.model import Scene

#: static predicates whose atoms perception re-derives (they follow the object's orientation)
ORIENTATION_PREFIXES = ("(force ", "(base ")


@dataclass(frozen=True)
class Executed:
    """One executed macro action: the backend's result, the injected fault, what was perceived."""

    macro: MacroResult
    fault: Fault | None
    perception: Perception
    perceive_s: float  # wall time of reading the physical state and abstracting it


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


class PhysicalGrounding:
    """A physics backend plus perception and fault injection (see the module docstring)."""

    def __init__(self, backend: PhysicsBackend, disturbance: float = 0.0) -> None:
        if disturbance > 0 and not isinstance(backend, Disturbable):
            raise ValueError(
                f"disturbance={disturbance} needs a backend that can inject faults "
                f"(a disturb(rng) method); {type(backend).__name__} has none"
            )
        self.backend, self.disturbance = backend, disturbance
        self._scene: Scene | None = None
        self.perception: Perception | None = None

    def reset(self, scene: Scene, rng: np.random.Generator) -> Perception:
        """Reset the simulator to `scene` (noise from `rng`) and perceive its state."""
        self.backend.reset(scene, rng)
        self._scene = scene
        return self._perceive()[0]

    def execute(self, action: str, rng: np.random.Generator) -> Executed:
        """Run `action`, maybe inject a fault (drawn from `rng`), then perceive."""
        macro = self.backend.execute(action)
        fault = None
        if self.disturbance > 0 and rng.random() < self.disturbance:
            assert isinstance(self.backend, Disturbable)
            fault = self.backend.disturb(rng)
        perception, seconds = self._perceive()
        return Executed(macro, fault, perception, seconds)

    def _perceive(self) -> tuple[Perception, float]:
        assert self._scene is not None
        start = time.perf_counter()
        self.perception = perceive(self._scene, self.backend.physical_state())
        return self.perception, time.perf_counter() - start
