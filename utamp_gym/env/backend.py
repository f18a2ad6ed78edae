"""The physics backend the env drives in ``grounding="physics"``: a protocol, not a class.

Why a protocol: the env only needs these calls, so the MuJoCo backend
(`DEFAULT_BACKEND`, written separately) and any other simulator can be swapped in through the
``backend`` option without the env importing MuJoCo.

The env constructs the backend once, as ``factory(**backend_kwargs)``, and calls `reset`
with the sampled scene and a generator derived from the env's RNG at every episode start.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from utamp_gym.errors import UnknownNameError
from utamp_gym.scene.model import Scene

DEFAULT_BACKEND = "utamp_gym.sim.backend:MujocoBackend"


@dataclass(frozen=True)
class MacroResult:
    """Outcome of one macro action in simulation; `timings` are seconds per phase."""

    success: bool
    reason: str | None = None
    timings: Mapping[str, float] = field(default_factory=dict)


@runtime_checkable
class PhysicsBackend(Protocol):
    """What the env needs from a simulator (see the module docstring)."""

    def reset(self, scene: Scene, rng: np.random.Generator) -> None: ...

    def execute(self, action: str) -> MacroResult: ...

    def object_poses(self) -> dict[str, np.ndarray]:
        """Object name -> ``[x, y, z, qw, qx, qy, qz]`` in the world frame."""
        ...

    def joint_positions(self) -> np.ndarray:
        """9 values: the 7 arm joints (rad) and the 2 finger joints (m)."""
        ...

    def stacked_on_tray(self) -> list[str]:
        """The tower on the tray, bottom to top, measured from the simulated poses."""
        ...

    def render(self, width: int, height: int) -> np.ndarray: ...

    def close(self) -> None: ...


def backend_factory(spec: str | Callable[..., PhysicsBackend]) -> Callable[..., PhysicsBackend]:
    """Resolve ``"module:Class"`` (or pass a callable through).

    Raises `ImportError` naming the spec if the module is missing (e.g. the MuJoCo backend
    is not installed), `UnknownNameError` if the module lacks the attribute.
    """
    if callable(spec):
        return spec
    module_name, sep, attr = str(spec).partition(":")
    if not sep or not module_name or not attr:
        raise ValueError(f"backend must be 'module:Class' or a callable, got {spec!r}")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ImportError(
            f"physics backend '{spec}' is not available ({exc}); use grounding='symbolic' "
            "or install/implement the backend"
        ) from exc
    try:
        return getattr(module, attr)
    except AttributeError:
        names = [n for n in dir(module) if not n.startswith("_")]
        raise UnknownNameError(f"attribute of {module_name}", attr, names) from None
