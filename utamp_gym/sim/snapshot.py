"""A simulated episode as plain data, and back: what pickling and deep-copying a physics env keep.

Why not pickle the MuJoCo objects: an `MjSpec` cannot be pickled at all, and a pickled `MjModel`
carries every mesh of the Panda. A `SimSnapshot` keeps what *determines* the world instead,
the scene and the objects' initial poses (the world is rebuilt from them, exactly as `reset`
built it), plus everything that changes while the episode runs: MuJoCo's full integration state
(`mujoco.mj_getState` with ``mjSTATE_INTEGRATION``: time, positions, velocities, controls,
actuator activations, the solver's warm start, ...), the generator, the robot's pose beliefs
(`PoseEstimator`, wrong-belief fault offsets included), the grasp it made and the retries of
the current action. `MujocoBackend` keeps its data forwarded between calls (derived quantities
match the state), so a restored copy steps bit for bit as the original does.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from utamp_gym.contract.tracking import PoseTracker
from utamp_gym.robot.kinematics import PandaKinematics
from utamp_gym.robot.panda_mjcf import add_panda, set_home
from utamp_gym.sim.cameras import add_wrist_camera
from utamp_gym.sim.control import ArmDriver, Timings
from utamp_gym.sim.estimate import PoseEstimator
from utamp_gym.sim.measure import Held, SimState, believed_qpos
from utamp_gym.sim.world import WorldInfo, build_world_spec, compile_world

#: MuJoCo's state that determines every later `mj_step`
FULL_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
#: sleeping islands (`sim.world`): which trees sleep and the awake sets derived from it. Not
#: part of MuJoCo's integration state, and `mj_forward` on data whose derived sets disagree
#: with ``tree_asleep`` wakes every tree, so all of them are kept and put back together.
SLEEP_ARRAYS = (
    "tree_asleep", "tree_awake", "body_awake", "body_awake_ind", "dof_awake_ind",
    "parent_awake_ind",
)  # fmt: skip
SLEEP_COUNTS = ("nbody_awake", "nparent_awake", "ntree_awake", "nv_awake")


@dataclass
class SimSnapshot:
    """One simulated episode at a point between macro actions (module docstring)."""

    info: WorldInfo
    timestep: float
    physics: np.ndarray
    rng: np.random.Generator
    estimator: PoseEstimator | PoseTracker | None
    held: Held | None = None
    retries: list[str] = field(default_factory=list)
    timings: Timings = field(default_factory=Timings)
    #: sleeping islands: whether the model has them, and their state (`SLEEP_ARRAYS`,
    #: `SLEEP_COUNTS`)
    sleep: bool = False
    asleep: dict[str, np.ndarray | int] = field(default_factory=dict)


def build_state(
    spec: mujoco.MjSpec,
    info: WorldInfo,
    kin: PandaKinematics,
    rng: np.random.Generator,
    estimator: PoseEstimator | PoseTracker | None,
) -> SimState:
    """The world of `spec` (from `build_world_spec`) with the Panda at its ready pose."""
    handles = add_panda(spec)
    add_wrist_camera(spec, handles.prefix)
    world = compile_world(spec, info)
    data = mujoco.MjData(world.model)
    ids = handles.bind(world.model)
    set_home(world.model, data, ids)
    arm = ArmDriver(world.model, data, ids, kin, rng)
    st = SimState(world, data, arm, scratch=mujoco.MjData(world.model), estimator=estimator)
    arm.belief = _belief_of(st)
    return st


def _belief_of(st: SimState) -> Callable[[np.ndarray], np.ndarray]:
    """`believed_qpos` of `st`, holding it weakly: the arm belongs to `st`, and a strong
    reference back would make a cycle that only the garbage collector frees, long after the
    episode's model and data (hundreds of MB over a few hundred resets) could have gone."""
    ref = weakref.ref(st)

    def belief(qpos: np.ndarray) -> np.ndarray:
        live = ref()
        return qpos if live is None else believed_qpos(live, qpos)

    return belief


def freeze(st: SimState) -> SimSnapshot:
    """The snapshot of `st` (shares its generator and estimator: copy the snapshot to detach)."""
    model, data = st.world.model, st.data
    physics = np.empty(mujoco.mj_stateSize(model, FULL_STATE))
    mujoco.mj_getState(model, data, physics, FULL_STATE)
    return SimSnapshot(
        info=st.world.info,
        timestep=float(model.opt.timestep),
        physics=physics,
        rng=st.arm.rng,
        estimator=st.estimator,
        held=st.held,
        retries=list(st.retries),
        timings=st.arm.timings,
        sleep=bool(model.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_SLEEP)),
        asleep={
            **{n: np.array(getattr(data, n)) for n in SLEEP_ARRAYS},
            **{n: int(getattr(data, n)) for n in SLEEP_COUNTS},
        },
    )


def thaw(snap: SimSnapshot, kin: PandaKinematics) -> SimState:
    """A live simulation in the state of `snap` (the world rebuilt from its scene and poses)."""
    spec, _ = build_world_spec(
        snap.info.scene,
        poses=snap.info.poses,
        appearance=snap.info.appearance or None,
        timestep=snap.timestep,
        sleep=snap.sleep,
    )
    st = build_state(spec, snap.info, kin, snap.rng, snap.estimator)
    mujoco.mj_setState(st.world.model, st.data, snap.physics, FULL_STATE)
    mujoco.mj_forward(st.world.model, st.data)
    if snap.asleep:
        for name, value in snap.asleep.items():
            if isinstance(value, np.ndarray):
                getattr(st.data, name)[:] = value
            else:
                setattr(st.data, name, value)
        mujoco.mj_forward(st.world.model, st.data)
    st.held, st.retries, st.arm.timings = snap.held, list(snap.retries), snap.timings
    return st
