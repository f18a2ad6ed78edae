"""The contract between a physics backend and the envs: a protocol and the types it exchanges.

Why a module below both `env/` and `sim/`: the env only needs these calls, so the MuJoCo
backend (`DEFAULT_BACKEND`) and any other simulator can be swapped in through the ``backend``
option without the env importing MuJoCo, and the simulator never imports the env.

The env constructs the backend once, as ``factory(pose_noise=..., **backend_kwargs)``, and
calls `reset` with the sampled scene and a generator derived from the env's RNG at every
episode start. After `reset` and after every `execute` it reads `physical_state()` and
perceives the symbolic state from it (`utamp_gym.perception`); ``utamp2-perceived`` surveys
the table (`survey`) and scores what it perceived by the cameras' instance ids (`cameras`):
that capability is `Surveying` (the symbolic backend has it too: it renders the episode's
initial world through the MuJoCo backend).
The data types exchanged live in `utamp_gym.contract` (below both the simulator and
perception); `MacroResult` and `Fault` here.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from utamp_gym.contract.state import PhysicalState
from utamp_gym.contract.views import ViewBundle
from utamp_gym.errors import UnknownNameError
from utamp_gym.scene.model import Scene

#: the MuJoCo simulator with the pose tracking the env option ``perception`` names
DEFAULT_BACKEND = "utamp_gym.grounding:physics_backend"
#: Standard deviation (m) of the robot's object-position estimates (env option `pose_noise`);
#: the yaw estimate's standard deviation scales with it (`yaw_noise_deg`).
DEFAULT_POSE_NOISE = 0.002
MAX_POSE_NOISE = 0.05
#: where the robot's object poses come from (env option ``perception``): ``gaussian``, the
#: true pose plus `pose_noise` (`utamp_gym.sim.estimate`), or ``rgbd``, poses fitted to the
#: rendered cameras (`utamp_gym.perception.tracking`; `utamp_gym.grounding` composes them)
PERCEPTION_MODES = ("gaussian", "rgbd")
DEFAULT_PERCEPTION = "gaussian"


def yaw_noise_deg(pose_noise: float) -> float:
    """Yaw estimation noise (deg) for a position noise (m): 2 deg per 5 mm."""
    return 2.0 * pose_noise / 0.005


#: The injected faults (issue "closed loop"): a push moves an object resting on the table or
#: on the tower by a few centimetres; a drop opens the gripper while it carries an object; a
#: belief fault offsets the robot's estimate of one object's pose (it acts on the offset
#: estimate until it grasps that object and re-estimates it).
FAULT_KINDS = ("push", "drop", "belief")


@dataclass(frozen=True)
class MacroResult:
    """Outcome of one macro action in simulation; `timings` are seconds per phase;
    `retries` says why an attempt within the action was undone and tried again (a grasp
    that missed, or an object that tilted or slipped in the first centimetre of its lift
    and was set back down)."""

    success: bool
    reason: str | None = None
    timings: Mapping[str, float] = field(default_factory=dict)
    retries: tuple[str, ...] = ()


@dataclass(frozen=True)
class Fault:
    """An injected fault: its kind (one of `FAULT_KINDS`), the object and what happened."""

    kind: str
    obj: str
    detail: str

    def __str__(self) -> str:
        return f"{self.kind} {self.obj}: {self.detail}"


class Cameras(Protocol):
    """A backend's RGB-D cameras, as the evaluation reads them."""

    @property
    def instances(self) -> Mapping[int, str]:
        """Instance id in the views' masks -> object name: the scorer's ground truth for
        what was perceived (never the perceiver's input)."""
        ...


@runtime_checkable
class PhysicsBackend(Protocol):
    """What the env needs from a simulator (see the module docstring). Backends with cameras
    also implement `Surveying` (the MuJoCo one does; the symbolic one renders its look through
    it)."""

    def reset(self, scene: Scene, rng: np.random.Generator) -> None: ...

    def execute(self, action: str) -> MacroResult: ...

    def physical_state(self) -> PhysicalState:
        """Poses, supports, containment and the grasp, as simulated now."""
        ...

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


@runtime_checkable
class Disturbable(Protocol):
    """A backend that can inject faults (needed by the env option ``disturbance`` > 0)."""

    def disturb(self, rng: np.random.Generator) -> Fault | None:
        """Inject one fault of `FAULT_KINDS` chosen with `rng` (None if none applies)."""
        ...


@runtime_checkable
class Surveying(Protocol):
    """A backend with cameras (the MuJoCo backend): what ``utamp2-perceived`` looks through.

    On Python 3.11 ``isinstance(backend, Surveying)`` reads `cameras`: check it after
    `reset`."""

    def survey(self) -> ViewBundle:
        """The first, careful look at the table: every scene camera's colour, depth and
        object-level instance masks, and the robot's state (what ``utamp2-perceived``
        perceives)."""
        ...

    @property
    def cameras(self) -> Cameras:
        """The cameras of the current episode (after `reset`)."""
        ...


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
