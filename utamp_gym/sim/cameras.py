"""RGB-D cameras of the kitchen world: fixed scene cameras and a wrist camera on the Panda.

Why in `sim`: rendering needs the MuJoCo world. What leaves this module is plain data
(`utamp_gym.contract.views`): images, intrinsics and camera poses, with **object-level**
instance masks — one id per object (1..N in the scene's object order), never per member or
geom, -1 for the robot's own body, 0 for everything else (table, floor). Handles, rims and
edges have to be found from geometry by the perceiver.

Cameras (`SCENE_CAMERAS`, `WRIST_CAMERA`; positions in the world frame: the robot base is
the origin, +x away from the robot, z = 0 the table top; each looks at its target with the
world's z axis up in the image; docs/perception.md lists them):

* two scene cameras above the table's sides (`ACTING_VIEWS`): the views of every look the
  robot takes while it acts (depth and instance masks at `ACTING_SIZE`);
* four more for the first, careful look at the table (`SURVEY_VIEWS` at `SURVEY_SIZE`, with
  colour): one across the table, one above it, and two low at the table's sides, which see
  under overhangs (a pan under a cutting board);
* ``wrist`` on the Panda hand, beside the fingers, looking along the approach and tilted
  towards the grasp axis, with about a RealSense D405's field of view (`WRIST_SIZE`).

Intrinsics follow from the image size and the field of view (pinhole, square pixels,
principal point at the image centre; `utamp_gym.contract.views.Intrinsics`). Rendering is
headless (EGL or OSMesa through ``MUJOCO_GL``) with shadows, reflections and skybox off:
320 x 240 costs a few milliseconds per image on these CPUs (`benchmarks/perception_cost.py`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.contract.views import (
    BACKGROUND,
    ROBOT,
    Intrinsics,
    RobotState,
    View,
    ViewBundle,
)
from utamp_gym.sim.offscreen import Offscreen

#: cameras of every look while acting, and of the first careful look
ACTING_VIEWS = ("scene-left", "scene-right")
SURVEY_VIEWS = (
    "scene-left",
    "scene-right",
    "scene-front",
    "scene-top",
    "scene-low-left",
    "scene-low-right",
)
WRIST = "wrist"
ACTING_SIZE = (320, 240)  # width, height
SURVEY_SIZE = (640, 480)
WRIST_SIZE = (240, 180)


@dataclass(frozen=True)
class CameraSpec:
    """A camera at `pos` looking at `target` (in its body's frame; `body` None: the world)."""

    name: str
    pos: tuple[float, float, float]
    target: tuple[float, float, float]
    fovy: float  # degrees, vertical
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    body: str | None = None

    def xyaxes(self) -> list[float]:
        """MuJoCo's camera x and y axes (it looks along -z) for this look-at."""
        z = np.asarray(self.pos, float) - np.asarray(self.target, float)
        z /= np.linalg.norm(z)
        x = np.cross(np.asarray(self.up, float), z)
        x /= np.linalg.norm(x)
        return [*x.tolist(), *np.cross(z, x).tolist()]


SCENE_CAMERAS: tuple[CameraSpec, ...] = (
    CameraSpec("scene-left", (0.60, 0.80, 0.90), (0.62, 0.0, 0.0), 60.0),
    CameraSpec("scene-right", (0.60, -0.80, 0.90), (0.62, 0.0, 0.0), 60.0),
    CameraSpec("scene-front", (1.55, 0.0, 0.95), (0.55, 0.0, 0.0), 55.0),
    CameraSpec("scene-top", (0.75, 0.0, 1.55), (0.62, 0.0, 0.0), 55.0, up=(1.0, 0.0, 0.0)),
    CameraSpec("scene-low-left", (0.50, 1.15, 0.16), (0.50, 0.0, 0.03), 50.0),
    CameraSpec("scene-low-right", (0.50, -1.15, 0.16), (0.50, 0.0, 0.03), 50.0),
)
#: on `panda_hand` (its z axis is the approach, y the finger axis); aimed 0.2 m down the
#: TCP axis, with the image's up towards the hand's +x side
WRIST_CAMERA = CameraSpec(
    WRIST, (0.07, 0.0, 0.03), (0.0, 0.0, 0.2), 75.0, up=(1.0, 0.0, 0.0), body="panda_hand"
)


def add_scene_cameras(spec: mujoco.MjSpec) -> None:
    """Add the fixed scene cameras to a world spec."""
    for cam in SCENE_CAMERAS:
        spec.worldbody.add_camera(
            name=cam.name, pos=list(cam.pos), xyaxes=cam.xyaxes(), fovy=cam.fovy
        )


def add_wrist_camera(spec: mujoco.MjSpec, prefix: str = "panda/") -> None:
    """Add the wrist camera to the Panda's hand (after `add_panda` attached it)."""
    cam = WRIST_CAMERA
    hand = spec.body(prefix + str(cam.body))
    if hand is None:
        raise ValueError(f"no body '{prefix}{cam.body}' to mount the wrist camera on")
    hand.add_camera(name=prefix + cam.name, pos=list(cam.pos), xyaxes=cam.xyaxes(), fovy=cam.fovy)


def intrinsics(fovy_deg: float, width: int, height: int) -> Intrinsics:
    """Pinhole intrinsics of a MuJoCo camera (square pixels, centred principal point)."""
    f = 0.5 * height / math.tan(math.radians(fovy_deg) / 2)
    return Intrinsics(width, height, f, f, width / 2 - 0.5, height / 2 - 0.5)


class CameraRig:
    """Renders the world's cameras into `ViewBundle` objects with object-level instance masks.

    `objects` maps each object name to its body id (instance ids follow this order, from 1);
    `robot_bodies` are the robot's bodies (instance -1). One offscreen renderer per image
    size is kept until `close`.

    A camera is rendered once per pose of the world: until a geom, camera or light moves
    (`_signature`), asking for it again returns the same `View` (read-only arrays). The
    skills look several times without the world moving between the looks (a wrist look,
    then the scene cameras' as well); the rasteriser would draw the same pixels again.
    The model is taken as fixed for the rig's life (a new world gets a new rig).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        objects: Mapping[str, int],
        robot_bodies: Iterable[int] = (),
        *,
        robot_prefix: str = "panda/",
    ) -> None:
        self.model = model
        self.names = tuple(objects)
        body_instance = np.zeros(model.nbody, dtype=np.int32)
        body_instance[np.fromiter(robot_bodies, dtype=int)] = ROBOT
        for i, body in enumerate(objects.values(), start=1):
            body_instance[body] = i
        self._geom_instance = body_instance[model.geom_bodyid]
        self._cameras = {
            name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, cam)
            for name, cam in [(c.name, c.name) for c in SCENE_CAMERAS]
            + [(WRIST, robot_prefix + WRIST)]
        }
        self._renderers: dict[tuple[int, int], Offscreen] = {}
        self._drawn: dict[tuple[str, tuple[int, int], bool], View] = {}  # at `_drawn_at`
        self._drawn_at = b""

    @property
    def instances(self) -> dict[int, str]:
        """Instance id -> object name."""
        return {i: n for i, n in enumerate(self.names, start=1)}

    def camera_names(self) -> tuple[str, ...]:
        return tuple(n for n, i in self._cameras.items() if i >= 0)

    def look(
        self,
        data: mujoco.MjData,
        cameras: Sequence[str],
        size: tuple[int, int],
        *,
        rgb: bool = True,
        robot: RobotState | None = None,
    ) -> ViewBundle:
        """Render `cameras` at `size` (width, height): depth, instance masks and (if `rgb`)
        colour, with each camera's intrinsics and pose."""
        now = _signature(data)
        if now != self._drawn_at:
            self._drawn.clear()
            self._drawn_at = now
        views = []
        for cam in cameras:
            view = self._drawn.get((cam, size, rgb))
            if view is None:
                view = self._drawn[cam, size, rgb] = self._view(data, cam, size, rgb)
            views.append(view)
        return ViewBundle(tuple(views), robot)

    def _renderer(self, size: tuple[int, int]) -> Offscreen:
        r = self._renderers.get(size)
        if r is None:
            r = self._renderers[size] = Offscreen(self.model, *size)
        return r

    def _view(self, data: mujoco.MjData, camera: str, size: tuple[int, int], rgb: bool) -> View:
        cid = self._cameras.get(camera, -1)
        if cid < 0:
            valid = ", ".join(self.camera_names())
            raise ValueError(f"unknown camera '{camera}'; valid: {valid}")
        r = self._renderer(size)
        r.update(data, cid)
        colour = r.colour() if rgb else None
        depth, geoms = r.depth_and_geoms()
        instances = np.where(geoms >= 0, self._geom_instance[geoms], BACKGROUND).astype(np.int32)
        pose = np.eye(4)
        pose[:3, :3] = data.cam_xmat[cid].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
        pose[:3, 3] = data.cam_xpos[cid]
        fovy = float(self.model.cam_fovy[cid])
        for array in (pose, depth, instances, colour):
            if array is not None:
                array.setflags(write=False)
        return View(camera, intrinsics(fovy, *size), pose, depth, instances, colour)

    def close(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers.clear()
        self._drawn.clear()


def _signature(data: mujoco.MjData) -> bytes:
    """What a rendering of `data` depends on besides the model: where every geom, camera and
    light is."""
    return b"".join(
        a.tobytes()
        for a in (
            data.geom_xpos,
            data.geom_xmat,
            data.cam_xpos,
            data.cam_xmat,
            data.light_xpos,
            data.light_xdir,
        )
    )


__all__ = [
    "ACTING_SIZE",
    "ACTING_VIEWS",
    "BACKGROUND",
    "ROBOT",
    "SCENE_CAMERAS",
    "SURVEY_SIZE",
    "SURVEY_VIEWS",
    "WRIST",
    "WRIST_CAMERA",
    "WRIST_SIZE",
    "CameraRig",
    "CameraSpec",
    "add_scene_cameras",
    "add_wrist_camera",
    "intrinsics",
]
