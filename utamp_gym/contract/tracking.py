"""Pose tracking: the robot's estimates of object poses, asked for while the backend acts.

Why a protocol here: the skills decode grasp, place and slide targets from *estimates*, and
they ask for them in the middle of a macro action (a look before each skill, the wrist
camera's re-look at an object in the hand). The simulator's own estimator is the true pose
plus Gaussian noise (`utamp_gym.sim.estimate.PoseEstimator`); estimates from images are
perception's (`utamp_gym.perception.tracking`), which the simulator must not import. So the
backend is handed a `PoseTracking` built above it, and at every reset it calls it with what
only the backend has: a `Look` that renders its cameras, the cameras' object instance ids,
the points on each object's surfaces it simulates, and each object's declared pose.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Protocol, runtime_checkable

import numpy as np

from utamp_gym.contract.views import ViewBundle
from utamp_gym.scene.model import Scene

#: renders one look: ``look(wrist_only)`` gives the wrist camera's views, and unless
#: `wrist_only` the acting scene cameras' too (depth and instance masks)
Look = Callable[[bool], ViewBundle]
#: points (N, 3) on an object's surfaces and their outward unit normals, object frame
Surface = tuple[np.ndarray, np.ndarray]


@runtime_checkable
class PoseTracker(Protocol):
    """What the skills ask of a pose estimator (`utamp_gym.sim.estimate.PoseEstimator`'s
    calls, 4x4 poses in the world); `noise` (m) is the error the grasps allow for,
    `offsets` the injected wrong beliefs, `seconds` / `cpu_seconds` the wall and CPU time
    spent looking (rendering and fitting)."""

    noise: float
    offsets: dict[str, tuple[np.ndarray, float]]
    seconds: list[float]
    cpu_seconds: float

    def new_look(self) -> None: ...

    def estimate(self, name: str, true_pose: np.ndarray) -> np.ndarray: ...

    def close_look(self, name: str, true_pose: np.ndarray) -> np.ndarray: ...

    def offset(self, name: str, shift: np.ndarray, yaw: float = 0.0) -> None: ...

    def forget(self, *names: str) -> None: ...

    def attach(self, look: Look) -> None:
        """Render with `look` from now on (a backend restored from a pickle)."""
        ...


class PoseTracking(Protocol):
    """Builds an episode's `PoseTracker` (the backend calls it at every reset)."""

    def __call__(
        self,
        scene: Scene,
        look: Look,
        instances: Mapping[str, int],
        surfaces: Mapping[str, Surface],
        initial: Mapping[str, np.ndarray],
    ) -> PoseTracker:
        """`instances`: object -> its id in the views' instance masks; `surfaces`: the
        robot's model of each object; `initial`: each object's declared pose (4x4)."""
        ...


class Beliefs:
    """A tracker's injected wrong beliefs (`offsets`: name -> (shift (m), yaw (rad))) and its
    current look's estimates (4x4), the part every `PoseTracker` keeps alike."""

    def __init__(self) -> None:
        self.offsets: dict[str, tuple[np.ndarray, float]] = {}
        self._look: dict[str, np.ndarray] = {}

    def offset(self, name: str, shift: np.ndarray, yaw: float = 0.0) -> None:
        """Make the robot believe `name` is `shift` (m, world) and `yaw` (rad) off."""
        self.offsets[name] = (np.asarray(shift, dtype=float).copy(), float(yaw))

    def forget(self, *names: str) -> None:
        """Drop the belief offsets and estimates of `names`: the robot looks at them again."""
        for name in names:
            self.offsets.pop(name, None)
            self._look.pop(name, None)


def rot_z(yaw: float) -> np.ndarray:
    """The 3x3 rotation by `yaw` (rad) about the vertical."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def shifted(pose: np.ndarray, shift: np.ndarray, yaw: float) -> np.ndarray:
    """A copy of `pose` (4x4, world) turned by `yaw` (rad) about the vertical where it
    stands and moved by `shift` (m, world): an estimate off by a belief offset or noise."""
    out = pose.copy()
    if yaw == 0.0 and not shift.any():
        return out
    out[:3, :3] = rot_z(yaw) @ pose[:3, :3]
    out[:3, 3] = pose[:3, 3] + shift
    return out


__all__ = ["Beliefs", "Look", "PoseTracker", "PoseTracking", "Surface", "rot_z", "shifted"]
