"""`RgbdPoseEstimator`: the robot's object poses fitted to a backend's RGB-D views.

The drop-in alternative to the simulator's Gaussian stand-in
(`utamp_gym.sim.estimate.PoseEstimator`), chosen with ``perception="rgbd"``: the backend is
handed `rgbd_tracking` (a `utamp_gym.contract.tracking.PoseTracking`) and calls it at every
reset with its `Look`, its cameras' instance ids, the points on each object's surfaces and
the declared poses. A *look* renders the acting cameras (depth and object-level instance
masks) and the wrist camera, fuses them (`perception.cloud.fuse`) and fits each object's
pose when it is first asked for (`perception.poses.estimate_pose`: iterative closest points
against the robot's model of the object, `PoseModel` with the surface points the backend
gave). Within a look an object's estimate stays the same; `forget` makes the next estimate
of an object come from a new rendering (the wrist camera's alone if it sees the object
well: the object in the hand), `new_look` does so for all. `close_look` renders the wrist
camera alone. An object the cameras cannot see (fewer than `poses.MIN_POINTS` points) keeps
its last estimate. Injected wrong beliefs (`offset`) are added to the camera estimate until
forgotten, as in the Gaussian model.

It never reads the simulator's poses: `estimate` takes the true pose for the interface's
sake and ignores it. The first belief is the scene's declared pose (orientation and
heading: the symbolic state the robot is given).
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np

from utamp_gym.contract.tracking import Beliefs, Look, Surface, shifted
from utamp_gym.perception.cloud import Scene3D, fuse
from utamp_gym.perception.poses import PoseModel, estimate_pose
from utamp_gym.scene.model import Scene

#: the standard deviation (m) the grasps' finger openings allow for, as the Gaussian
#: model's `noise` does (the measured error: benchmarks/perception_cost.py)
RGBD_NOISE = 0.002
WRIST_POINTS = 150  # an object this well seen by the wrist camera needs no scene look ...
WHOLE_SPAN = 0.8  # ... if its points span this much of its longest extent
STILL = 0.0005  # m: an object whose points' centre moved less than this was not refitted


class RgbdPoseEstimator(Beliefs):
    """Object poses from the cameras (module docstring)."""

    def __init__(
        self,
        look: Look,
        instances: Mapping[str, int],
        models: Mapping[str, PoseModel],
        initial: Mapping[str, np.ndarray],
    ) -> None:
        super().__init__()
        self.noise = RGBD_NOISE
        self._render, self._ids, self._models = look, dict(instances), dict(models)
        self._belief = {n: np.asarray(p, dtype=float).copy() for n, p in initial.items()}
        self._frames: Scene3D | None = None
        self._again: set[str] = set()  # looked at again: try the wrist camera first
        self._tcp: np.ndarray | None = None  # the hand's pose at the last rendering
        self._belief_tcp: dict[str, np.ndarray] = {}  # ... when each belief was formed
        self._signature: dict[str, tuple[int, np.ndarray]] = {}  # points when last fitted
        self.seconds: list[float] = []  # wall time of every rendering + fit (perception cost)
        self.cpu_seconds = 0.0  # ... and the process's CPU time spent on them

    def attach(self, look: Look) -> None:
        """Render with `look` from now on (a backend restored from a pickle)."""
        self._render = look

    def __getstate__(self) -> dict[str, object]:
        """Pickled without its renderer (the backend attaches its own) or a stale look."""
        state = dict(self.__dict__)
        state["_render"], state["_frames"] = None, None
        return state

    def new_look(self) -> None:
        self._look.clear()
        self._again.clear()
        self._frames = None

    def estimate(self, name: str, true_pose: np.ndarray) -> np.ndarray:
        """The camera estimate (4x4) of `name` in the current look (`true_pose` unused).
        An object looked at again (`forget`) is first looked for with the wrist camera
        alone (the object in the hand, the one the hand is at)."""
        seen = self._look.get(name)
        if seen is None:
            if name in self._again:
                self._again.discard(name)
                wrist = self._fused(wrist_only=True)
                if self._whole(name, wrist):
                    seen = self._look[name] = self._fit(name, wrist)
                    return self._with_offset(name, seen)
            if self._frames is None:
                self._frames = self._fused(wrist_only=False)
            seen = self._look[name] = self._fit(name, self._frames)
        return self._with_offset(name, seen)

    def close_look(self, name: str, true_pose: np.ndarray) -> np.ndarray:
        """The wrist camera's look at `name` (`true_pose` unused); its belief offset ends."""
        self.offsets.pop(name, None)
        frames = self._fused(wrist_only=True)
        if not self._whole(name, frames):  # partly out of the wrist's view: the scene's too
            frames = self._fused(wrist_only=False)
        self._look[name] = self._fit(name, frames)
        return self._look[name].copy()

    def forget(self, *names: str) -> None:
        super().forget(*names)
        self._again.update(names)
        self._frames = None

    # ------------------------------------------------------------ internals
    def _whole(self, name: str, frames: Scene3D) -> bool:
        """Whether `frames` show enough of `name` to fit its pose: `WRIST_POINTS` points
        spanning at least `WHOLE_SPAN` of its model's longest horizontal extent (a part of a
        board's flat top would let a fit slide along it)."""
        cloud = frames.objects.get(self._ids[name])
        if cloud is None or len(cloud) < WRIST_POINTS:
            return False
        surface = self._models[name].surface
        if surface is None:
            return True
        model_span = float(np.max(np.ptp(surface[:, :2], axis=0)))
        seen = cloud.points[:, :2]
        span = float(np.max(np.ptp(seen, axis=0)))
        return span >= WHOLE_SPAN * model_span

    def _fused(self, *, wrist_only: bool) -> Scene3D:
        start, cpu = time.perf_counter(), time.process_time()
        bundle = self._render(wrist_only)
        frames = fuse(bundle, objects_only=True)
        self._tcp = None if bundle.robot is None else bundle.robot.tcp
        self.seconds.append(time.perf_counter() - start)
        self.cpu_seconds += time.process_time() - cpu
        return frames

    def _fit(self, name: str, frames: Scene3D) -> np.ndarray:
        start, cpu = time.perf_counter(), time.process_time()
        try:
            return self._fit_timed(name, frames)
        finally:
            self.seconds[-1] += time.perf_counter() - start
            self.cpu_seconds += time.process_time() - cpu

    def _fit_timed(self, name: str, frames: Scene3D) -> np.ndarray:
        cloud = frames.objects.get(self._ids[name])
        prior = self._belief[name]
        if cloud is not None and self._unchanged(name, cloud.points):
            return prior.copy()  # seen just as before: it has not moved
        then = self._belief_tcp.get(name)
        # where the hand would have carried it since it was last seen (if it holds it)
        starts = (
            () if then is None or self._tcp is None else (self._tcp @ np.linalg.inv(then) @ prior,)
        )
        pose = (
            None
            if cloud is None
            else estimate_pose(cloud.points, self._models[name], prior, starts)
        )
        if pose is not None:
            self._belief[name] = pose
            if self._tcp is not None:
                self._belief_tcp[name] = self._tcp
        return self._belief[name].copy()

    def _unchanged(self, name: str, points: np.ndarray) -> bool:
        """Whether `name` shows the same points as when it was last fitted (same cameras,
        about as many points, the same centre within `STILL`): then its pose is kept."""
        key = (len(points), points.mean(axis=0))
        last = self._signature.get(name)
        self._signature[name] = key
        if last is None or self._tcp is None:
            return False
        n0, c0 = last
        return abs(key[0] - n0) <= 0.02 * n0 and float(np.linalg.norm(key[1] - c0)) <= STILL

    def _with_offset(self, name: str, pose: np.ndarray) -> np.ndarray:
        shift, yaw = self.offsets.get(name, (np.zeros(3), 0.0))
        return shifted(pose, shift, yaw)


def rgbd_tracking(
    scene: Scene,
    look: Look,
    instances: Mapping[str, int],
    surfaces: Mapping[str, Surface],
    initial: Mapping[str, np.ndarray],
) -> RgbdPoseEstimator:
    """The `PoseTracking` of ``perception="rgbd"``: an `RgbdPoseEstimator` whose model of
    each object is its catalogue type's `PoseModel` with the backend's surface points."""
    models = {n: PoseModel.of(scene.type_of(n)).with_surface(*surfaces[n]) for n in surfaces}
    return RgbdPoseEstimator(look, instances, models, initial)


__all__ = ["RGBD_NOISE", "RgbdPoseEstimator", "rgbd_tracking"]
