"""`MujocoBackend`: the physics backend of the Gym env (see `utamp_gym.backend`).

`reset` builds the scene's MuJoCo world with a Panda at the origin in its ready pose
(with sleeping islands on: objects at rest cost nothing until touched, `sim.world`),
draws the initial pose noise from the given generator and lets everything settle;
`execute` runs one U-TAMP-2 macro action through `skills`; `physical_state` reports what
perception needs; `disturb` injects a fault (`faults`). Everything random (initial pose
noise, pose-estimation noise, IK restarts, OMPL seeds) is drawn from the generator given
to `reset`, and faults from the one given to `disturb`, so the same seeds give the same
rollout. Rendering is headless (`utamp_gym.sim.gl` picks a working OpenGL backend when
``MUJOCO_GL`` is unset) and cheap: shadows, reflections and skybox are off.

**Frames while an action runs.** A macro action simulates several seconds; to see them,
`watch(callback, period)` has `callback()` called every `period` s of simulated time while
the physics steps (inside `execute` and `disturb`): a video recorder renders then (`render`),
a live viewer syncs with `model` / `data`. `frame_sink` is the shortcut for videos: it
receives an RGB frame (`frame_size` = width, height) every `frame_period` s. With no watcher
and no sink the physics steps in bulk (no per-step Python call).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import mujoco
import numpy as np

from utamp_gym.backend import DEFAULT_PERCEPTION, DEFAULT_POSE_NOISE, Fault, MacroResult
from utamp_gym.contract.state import Grasp, PhysicalState
from utamp_gym.contract.tracking import PoseTracker, PoseTracking
from utamp_gym.contract.views import RobotState, ViewBundle
from utamp_gym.errors import GroundingError, SimulationError, UnknownNameError
from utamp_gym.robot.kinematics import PandaKinematics
from utamp_gym.scene.model import Scene
from utamp_gym.sim.cameras import (
    ACTING_SIZE,
    ACTING_VIEWS,
    SURVEY_SIZE,
    SURVEY_VIEWS,
    WRIST,
    WRIST_SIZE,
    CameraRig,
)
from utamp_gym.sim.control import Timings
from utamp_gym.sim.decode import parse_action, pose_of
from utamp_gym.sim.estimate import PoseEstimator
from utamp_gym.sim.faults import disturb
from utamp_gym.sim.gl import new_renderer
from utamp_gym.sim.heap import release_free_memory
from utamp_gym.sim.measure import SimState, settle_objects
from utamp_gym.sim.physical import FLOOR_BELOW, measure_state, object_poses
from utamp_gym.sim.skills import run_skill
from utamp_gym.sim.snapshot import build_state, freeze, thaw
from utamp_gym.sim.surfaces import surface_points
from utamp_gym.sim.world import build_world_spec, rests_on_top

CAMERA = "overview"
TIPPED_BELOW = 0.02  # m (see `MujocoBackend._camera_poses`)
#: receives one RGB frame (height, width, 3) of the overview camera
FrameSink = Callable[[np.ndarray], None]
__all__ = ["CAMERA", "FLOOR_BELOW", "FrameSink", "MujocoBackend"]


class MujocoBackend:
    """Simulated Panda executing macro actions on a kitchen table (MuJoCo + Pinocchio + OMPL).

    `pos_noise` (m) and `yaw_noise_deg` randomise where the scene's objects start (uniform,
    per episode). `pose_noise` (m) is the robot's pose-estimation error: grasp, place and
    slide targets are decoded from estimates (`utamp_gym.sim.estimate`), never from the
    simulator's truth. `perception` is ``"gaussian"`` (that model: the true pose plus
    `pose_noise`) or a `PoseTracking` built above the simulator (`utamp_gym.contract.tracking`),
    e.g. ``perception.tracking.rgbd_tracking``, which fits poses to the rendered cameras
    (`pose_noise` is then unused, and the poses of `physical_state` are its estimates too;
    ``utamp_gym.grounding.physics_backend(perception="rgbd")`` builds that). `frame_sink`
    (settable at any time; None: off) receives an RGB frame (`frame_size` = width, height)
    every `frame_period` s of simulated time while actions run (for videos); `watch`
    registers any per-period callback (module docstring).
    """

    def __init__(
        self,
        *,
        pos_noise: float = 0.003,
        yaw_noise_deg: float = 2.0,
        pose_noise: float = DEFAULT_POSE_NOISE,
        perception: str | PoseTracking = DEFAULT_PERCEPTION,
        settle_s: float = 0.5,
        frame_sink: FrameSink | None = None,
        frame_period: float = 0.1,
        frame_size: tuple[int, int] = (480, 360),
    ):
        self.pos_noise, self.yaw_noise_deg, self.settle_s = pos_noise, yaw_noise_deg, settle_s
        self.pose_noise = pose_noise
        if isinstance(perception, str) and perception != DEFAULT_PERCEPTION:
            raise ValueError(
                f"MujocoBackend(perception={perception!r}): the simulator fits no poses; pass a "
                "PoseTracking (e.g. utamp_gym.perception.tracking.rgbd_tracking) or build it "
                f"with utamp_gym.grounding.physics_backend(perception={perception!r})"
            )
        #: the pose tracking handed in (None: the Gaussian model of `utamp_gym.sim.estimate`)
        self.tracking: PoseTracking | None = None if isinstance(perception, str) else perception
        if frame_period <= 0:
            raise ValueError(f"frame_period must be > 0 s, got {frame_period!r}")
        self.frame_period, self.frame_size = frame_period, frame_size
        self._kin: PandaKinematics | None = None
        self._state: SimState | None = None
        self._rig: CameraRig | None = None
        self._renderers: dict[tuple[int, int], mujoco.Renderer] = {}
        self._steps = 0
        self._watchers: dict[int, tuple[Callable[[], None], float]] = {}
        self._tokens = itertools.count()
        self._frame_sink: FrameSink | None = None
        self.frame_sink = frame_sink

    # ------------------------------------------------------------ protocol
    def reset(self, scene: Scene, rng: np.random.Generator) -> None:
        """Build the scene's world (+ Panda at home) with seeded pose noise and settle it."""
        self._close_renderers()
        self._state = None  # the previous episode's memory is free before the next is built
        if self._kin is None:
            self._kin = PandaKinematics()
        spec, info = build_world_spec(
            scene,
            rng=rng,
            pos_noise=self.pos_noise,
            yaw_noise_deg=self.yaw_noise_deg,
            sleep=True,
        )
        estimator = PoseEstimator(self.pose_noise, rng)
        self._state = build_state(spec, info, self._kin, rng, estimator)
        if self.tracking is not None:
            self._state.estimator = self._tracker(scene, self.tracking)
        self._steps = 0
        self._hook()
        settle_objects(self._state, min_s=self.settle_s, max_s=self.settle_s + 1.0)
        self._state.arm.timings = Timings()
        self._rest()
        release_free_memory()  # keeps a long run's resident size flat (`utamp_gym.sim.heap`)

    def execute(self, action: str) -> MacroResult:
        """Run one grounded PDDL macro action; a failure comes back with a reason. With a
        pose tracking its timings include ``perception_s`` (wall) and
        ``perception_cpu_s`` (this process's CPU time): rendering and fitting."""
        st = self._require()
        try:
            act = parse_action(action, st.world.scene)
        except (GroundingError, UnknownNameError) as exc:
            return MacroResult(False, f"invalid action {action}: {exc}", Timings().as_dict(0.0))
        est = self._tracked()
        before = self._perception_seconds()
        cpu = est.cpu_seconds if est is not None else 0.0
        result = run_skill(st, act)
        self._rest()
        if est is not None:
            timings = {
                **result.timings,
                "perception_s": self._perception_seconds() - before,
                "perception_cpu_s": est.cpu_seconds - cpu,
            }
            result = replace(result, timings=timings)
        return result

    # ------------------------------------------------------------ pose tracking
    def _tracker(self, scene: Scene, tracking: PoseTracking) -> PoseTracker:
        """This episode's tracker: handed the cameras' look, their instance ids, the
        robot's model of each object (`surfaces.surface_points`) and the declared poses."""
        st = self._require()
        ids = {name: i for i, name in self.cameras.instances.items()}
        surfaces = {n: surface_points(scene.type_of(n)) for n in st.world.body_ids}
        declared = {n: pose_of(p.position, p.quat) for n, p in scene.poses.items()}
        self._pose_look(False)  # the cameras' renderers, made before the first action
        return tracking(scene, self._pose_look, ids, surfaces, declared)

    def _tracked(self) -> PoseTracker | None:
        """The episode's pose tracker, or None with the Gaussian model."""
        return None if self.tracking is None else self._require().estimator

    def _pose_look(self, wrist_only: bool) -> ViewBundle:
        """The views of one look while acting: the wrist camera, and unless `wrist_only`
        the acting scene cameras (depth and instance masks only)."""
        st, rig = self._require(), self.cameras
        wrist = rig.look(st.data, (WRIST,), WRIST_SIZE, rgb=False).views
        if wrist_only:
            return ViewBundle(wrist, self.robot_state())
        scene = rig.look(st.data, ACTING_VIEWS, ACTING_SIZE, rgb=False).views
        return ViewBundle(scene + wrist, self.robot_state())

    def _perception_seconds(self) -> float:
        est = self._tracked()
        return float(sum(est.seconds)) if est is not None else 0.0

    def physical_state(self) -> PhysicalState:
        """Poses, what carries each object (contact forces), containment and the grasp
        (`utamp_gym.sim.physical.measure_state`; the grasp is the one the pick skill made,
        while the fingers still hold something)."""
        st = self._require()
        held = None
        if st.held is not None and st.arm.holds_something():
            sym = st.held.symbols
            held = Grasp(sym.obj, sym.member, sym.palm, sym.finger1, sym.finger2)
        state = measure_state(
            st.world, st.data, held=held, gripper_gap=st.arm.gap(), scratch=st.scratch
        )
        if self.tracking is not None:
            state = replace(state, poses=self._camera_poses())
        return state

    def _camera_poses(self) -> dict[str, tuple[float, ...]]:
        """Every object's pose as the cameras see it now (a new look). An object whose
        estimated bottom lies more than `TIPPED_BELOW` under the table has tipped over (a
        level pose cannot explain it): it is reported turned on its side."""
        st = self._require()
        est = self._tracked()
        assert est is not None
        est.new_look()
        quat = np.zeros(4)
        out = {}
        for name in st.world.body_ids:
            pose = est.estimate(name, np.eye(4))
            box = st.world.scene.type_of(name).bbox
            bottom = pose[2, 3] + (box.min[2] if pose[2, 2] > 0 else -box.max[2])
            if bottom < -TIPPED_BELOW:
                pose = pose @ pose_of(np.zeros(3), np.array([0.7071, 0.7071, 0.0, 0.0]))
            mujoco.mju_mat2Quat(quat, pose[:3, :3].ravel())
            out[name] = (*(float(v) for v in pose[:3, 3]), *(float(v) for v in quat))
        return out

    def disturb(self, rng: np.random.Generator) -> Fault | None:
        """Inject one fault (`utamp_gym.sim.faults`), chosen with `rng`."""
        fault = disturb(self._require(), rng)
        self._rest()
        return fault

    def object_poses(self) -> dict[str, np.ndarray]:
        """Object name -> [x, y, z, qw, qx, qy, qz] of its frame in the world."""
        st = self._require()
        return object_poses(st.world, st.data)

    def joint_positions(self) -> np.ndarray:
        """7 arm joint angles (rad) and 2 finger positions (m)."""
        st = self._require()
        ids = st.arm.ids
        return np.concatenate([st.data.qpos[ids.arm_qpos_adr], st.data.qpos[ids.finger_qpos_adr]])

    def stacked_on_tray(self) -> list[str]:
        """Objects standing on the tower base, bottom to top (base excluded), as simulated."""
        st = self._require()
        stack = st.stack()
        out: list[str] = []
        cur = st.world.scene.tower_base
        while True:
            above = [
                o
                for o, s in stack.items()
                if s == cur and o not in out and rests_on_top(st.world, st.data, o, cur)
            ]
            if not above:
                return out
            cur = above[0]
            out.append(cur)

    def render(self, width: int, height: int) -> np.ndarray:
        """RGB image (height, width, 3) from the overview camera."""
        st = self._require()
        key = (int(width), int(height))
        renderer = self._renderers.get(key)
        if renderer is None:
            vis = st.world.model.vis.global_
            vis.offwidth, vis.offheight = max(vis.offwidth, key[0]), max(vis.offheight, key[1])
            renderer = self._renderers[key] = new_renderer(st.world.model, key[1], key[0])
        renderer.update_scene(st.data, camera=CAMERA)
        for flag in (
            mujoco.mjtRndFlag.mjRND_SHADOW,
            mujoco.mjtRndFlag.mjRND_REFLECTION,
            mujoco.mjtRndFlag.mjRND_SKYBOX,
        ):
            renderer.scene.flags[flag] = 0
        return renderer.render()

    def close(self) -> None:
        self._close_renderers()
        self._state = None

    # ------------------------------------------------------------ cameras
    @property
    def cameras(self) -> CameraRig:
        """The world's RGB-D cameras (`utamp_gym.sim.cameras`), made on first use."""
        st = self._require()
        if self._rig is None or self._rig.model is not st.world.model:
            if self._rig is not None:
                self._rig.close()
            self._rig = CameraRig(st.world.model, st.world.body_ids, st.arm.ids.body_ids)
        return self._rig

    def survey(self) -> ViewBundle:
        """The first, careful look at the table: every scene camera, colour, depth and
        instance masks at `cameras.SURVEY_SIZE` (what `utamp2-perceived` perceives)."""
        st = self._require()
        return self.cameras.look(st.data, SURVEY_VIEWS, SURVEY_SIZE, robot=self.robot_state())

    def robot_state(self) -> RobotState:
        """The robot's own state (joints, finger gap, TCP pose)."""
        st = self._require()
        return RobotState(st.arm.q(), st.arm.gap(), st.arm.tcp())

    # ------------------------------------------------------------ pickling
    def __getstate__(self) -> dict[str, Any]:
        """The simulation as a `SimSnapshot` (`utamp_gym.sim.snapshot`): the world is rebuilt
        from its scene on load and continues bit for bit. Renderers, watchers and the frame
        sink are not pickled (whoever watched attaches again, as the env's rendering does)."""
        state = {k: v for k, v in self.__dict__.items() if k not in _NOT_PICKLED}
        state["_state"] = None if self._state is None else freeze(self._state)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        snapshot = state.pop("_state")
        self.__dict__.update(state)
        self._renderers, self._watchers, self._tokens = {}, {}, itertools.count()
        self._frame_sink = None
        if snapshot is not None and self._kin is None:
            self._kin = PandaKinematics()
        self._state = None if snapshot is None else thaw(snapshot, self._kin)
        self._rig = None
        est = None if self._state is None else self._tracked()
        if est is not None:
            est.attach(self._pose_look)  # its cameras are this backend's
        self._hook()

    # ------------------------------------------------------------ frames
    @property
    def frame_sink(self) -> FrameSink | None:
        """Receives an RGB frame every `frame_period` s of simulated time (None: off)."""
        return self._frame_sink

    @frame_sink.setter
    def frame_sink(self, sink: FrameSink | None) -> None:
        self._frame_sink = sink
        self._hook()

    def watch(self, callback: Callable[[], None], period: float) -> Callable[[], None]:
        """Call `callback()` every `period` s of simulated time while the physics steps.

        Returns a function that stops the calls. Watchers survive `reset`.
        """
        if period <= 0:
            raise ValueError(f"period must be > 0 s, got {period!r}")
        token = next(self._tokens)
        self._watchers[token] = (callback, period)
        self._hook()

        def unwatch() -> None:
            self._watchers.pop(token, None)
            self._hook()

        return unwatch

    @property
    def model(self) -> mujoco.MjModel:
        """The live model (a new one after every `reset`), e.g. for a viewer."""
        return self._require().world.model

    @property
    def data(self) -> mujoco.MjData:
        """The live simulation data (read it; stepping it is the backend's job)."""
        return self._require().data

    # ------------------------------------------------------------ helpers
    @property
    def state(self) -> SimState:
        """The live simulation (world, data, arm); for tests and tools."""
        return self._require()

    def _require(self) -> SimState:
        if self._state is None:
            raise SimulationError("MujocoBackend: call reset(scene, rng) first")
        return self._state

    def _hook(self) -> None:
        """Step one by one (calling `_on_step`) only while someone watches."""
        if self._state is not None:
            watched = self._frame_sink is not None or bool(self._watchers)
            self._state.arm.on_step = self._on_step if watched else None

    def _rest(self) -> None:
        """Between calls the data is forwarded: what is read (poses, contacts) belongs to the
        current state, and a snapshot of the state restores everything (`mj_step` depends on
        the integration state only, so the trajectory is the same)."""
        st = self._require()
        mujoco.mj_forward(st.world.model, st.data)

    def _on_step(self) -> None:
        self._steps += 1
        st = self._state
        if st is None:
            return
        dt = st.arm.dt
        if self._frame_sink is not None and self._steps % _every(self.frame_period, dt) == 0:
            self._frame_sink(self.render(*self.frame_size))
        for callback, period in list(self._watchers.values()):
            if self._steps % _every(period, dt) == 0:
                callback()

    def _close_renderers(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers.clear()
        if self._rig is not None:
            self._rig.close()
            self._rig = None


#: live objects a pickled backend leaves behind (`MujocoBackend.__getstate__`)
_NOT_PICKLED = ("_renderers", "_watchers", "_tokens", "_frame_sink", "_rig")


def _every(period: float, dt: float) -> int:
    """Physics steps per `period` s (at least one)."""
    return max(1, round(period / dt))
