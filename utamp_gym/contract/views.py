"""What the perceiver is given: rendered RGB-D views, camera parameters, the robot's state.

Why plain data: the perceiver (`utamp_gym.perception.objects`, `utamp_gym.perception.poses`)
must never read the scene, its object types or the simulator's geoms and bodies. Its whole
input is a `ViewBundle`: per camera the colour image, the metric depth, an **object-level**
instance mask (one id per object; 0 for the background, -1 for the robot's own body), the
pinhole intrinsics and the camera's pose in the world; plus the robot's own state (joint
positions, finger gap, hand pose). Any renderer or real RGB-D driver can fill it in; the
MuJoCo one is `utamp_gym.sim.cameras.CameraRig`.

Conventions: camera frames are the computer-vision ones (x right, y down, z forward); depth
is the distance along the optical axis in metres; `Intrinsics.cx`, `cy` are in pixel-index
coordinates (the centre of pixel (0, 0) is (0, 0)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BACKGROUND, ROBOT = 0, -1


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole camera intrinsics (pixels)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float


@dataclass(frozen=True)
class RobotState:
    """The robot's own state: arm joints (rad), finger gap (m), TCP pose (4x4, world)."""

    joints: np.ndarray
    gripper_gap: float
    tcp: np.ndarray


@dataclass(frozen=True, eq=False)
class View:
    """One camera image set: depth (H, W) metres, instances (H, W) int, rgb (H, W, 3) or None.

    `world_from_camera` (4x4) maps camera-frame points to the world.
    """

    camera: str
    intrinsics: Intrinsics
    world_from_camera: np.ndarray
    depth: np.ndarray
    instances: np.ndarray
    rgb: np.ndarray | None = None

    def points(self, mask: np.ndarray | None = None) -> np.ndarray:
        """World points (N, 3) of the pixels in `mask` (default: every pixel), row-major."""
        k = self.intrinsics
        if mask is None:
            mask = np.ones(self.depth.shape, dtype=bool)
        v, u = np.nonzero(mask)
        z = self.depth[v, u].astype(float)
        cam = np.stack([(u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z], axis=1)
        rot, pos = self.world_from_camera[:3, :3], self.world_from_camera[:3, 3]
        return cam @ rot.T + pos

    @property
    def position(self) -> np.ndarray:
        return self.world_from_camera[:3, 3]

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pixel columns, rows (float) and depths of world `points` (N, 3)."""
        k = self.intrinsics
        inv = np.linalg.inv(self.world_from_camera)
        cam = points @ inv[:3, :3].T + inv[:3, 3]
        z = cam[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            return cam[:, 0] / z * k.fx + k.cx, cam[:, 1] / z * k.fy + k.cy, z


@dataclass(frozen=True, eq=False)
class ViewBundle:
    """Everything one look gives the perceiver: the views and the robot's state."""

    views: tuple[View, ...]
    robot: RobotState | None = None

    def instance_ids(self) -> list[int]:
        """Object instance ids seen in any view (sorted)."""
        ids: set[int] = set()
        for v in self.views:
            ids.update(int(i) for i in np.unique(v.instances) if i > 0)
        return sorted(ids)


__all__ = ["BACKGROUND", "ROBOT", "Intrinsics", "RobotState", "View", "ViewBundle"]
