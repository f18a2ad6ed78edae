"""Injected faults: a push, a drop, a wrong belief (`utamp_gym.backend.FAULT_KINDS`).

Why: a closed-loop system is judged by how it recovers from the unexpected, so the
benchmark can disturb an episode on purpose (env option ``disturbance``). Every fault is
physical or epistemic, never symbolic: the simulator moves objects and physics decides what
follows (a pushed stack may topple), or the robot's pose estimate of one object is offset
(`PoseEstimator.offset`). All choices come from the generator the caller passes (the env's).

* **push** – an object resting on the table or on a stack (not the held one) is pushed
  horizontally by `PUSH_RANGE` metres in a random direction, at `PUSH_SPEED`, the way a
  flat pusher (a palm, a sliding tray's edge) pushes it: along its whole side, so it slides
  without turning; what rests on it is carried along by friction or not. A push through
  the centre of mass alone — a finger at mid-height — tips any object whose friction
  moment exceeds its footprint's (μ·h > r: the shaker, an upright mug), an unrecoverable
  state in U-TAMP-2, which has no action to right an object (measured with such pushes:
  10 of 12 closed-loop failures on pick-place at p = 0.1 ended with a toppled shaker or
  mug; see the README).
* **drop** – while the hand carries an object, the gripper opens; the object falls.
* **belief** – the robot's belief of one object's pose is offset by `BELIEF_RANGE` metres
  (and up to `BELIEF_YAW_DEG`) until it grasps the object or an action involving it fails.
"""

from __future__ import annotations

import math

import numpy as np

from utamp_gym.backend import Fault
from utamp_gym.robot.panda_mjcf import GRIPPER_MAX_GAP
from utamp_gym.sim.measure import SimState, obj_pose, settle_objects

PUSH_RANGE = (0.02, 0.04)  # m
PUSH_SPEED = 0.05  # m/s
BELIEF_RANGE = (0.01, 0.03)  # m
BELIEF_YAW_DEG = 5.0
DROP_WAIT_S = 0.3  # s the fingers take to open before the object is left to fall


def disturb(st: SimState, rng: np.random.Generator) -> Fault | None:
    """Inject one fault, its kind drawn uniformly among those that apply now."""
    free = [n for n in st.world.body_ids if st.held is None or n != st.held.obj]
    kinds = ["push", "belief"] if free else []
    if st.estimator is None and kinds:
        kinds.remove("belief")
    if st.held is not None:
        kinds.append("drop")
    if not kinds:
        return None
    kind = kinds[int(rng.integers(len(kinds)))]
    if kind == "drop":
        return drop(st)
    name = free[int(rng.integers(len(free)))]
    angle = float(rng.uniform(0.0, 2 * math.pi))
    direction = np.array([math.cos(angle), math.sin(angle), 0.0])
    if kind == "push":
        return push(st, name, direction, float(rng.uniform(*PUSH_RANGE)))
    distance = float(rng.uniform(*BELIEF_RANGE))
    yaw = math.radians(float(rng.uniform(-BELIEF_YAW_DEG, BELIEF_YAW_DEG)))
    assert st.estimator is not None
    st.estimator.offset(name, direction * distance, yaw)
    return Fault(
        "belief",
        name,
        f"the robot believes it {distance * 100:.1f} cm off (towards {_heading(direction)}) "
        f"and turned {math.degrees(yaw):.1f} deg",
    )


def push(st: SimState, name: str, direction: np.ndarray, distance: float) -> Fault:
    """Push `name` by `distance` m along `direction` (world, horizontal), then settle."""
    start = obj_pose(st, name)[:3, 3].copy()
    dof = st.world.dof_adr[name]
    n = max(1, round(distance / PUSH_SPEED / st.arm.dt))
    for _ in range(n):  # a flat pusher at constant speed: it sets the speed, holds the turn
        st.data.qvel[dof : dof + 2] = PUSH_SPEED * direction[:2]
        st.data.qvel[dof + 3 : dof + 6] = 0.0
        st.arm.step(1)
    settle_objects(st)
    moved = float(np.linalg.norm((obj_pose(st, name)[:3, 3] - start)[:2]))
    return Fault(
        "push",
        name,
        f"pushed {distance * 100:.1f} cm towards {_heading(direction)}; "
        f"it moved {moved * 100:.1f} cm",
    )


def drop(st: SimState) -> Fault:
    """Open the gripper while it carries an object and let it fall."""
    assert st.held is not None
    name = st.held.obj
    st.arm.open_gripper(GRIPPER_MAX_GAP, max_s=DROP_WAIT_S)
    st.held = None
    settle_objects(st)
    where = st.stack().get(name) or "nothing"
    return Fault("drop", name, f"the gripper opened while carrying it; it rests on {where}")


def _heading(direction: np.ndarray) -> str:
    """A compass-like name for a horizontal direction (+x away from the robot, +y left)."""
    return f"{math.degrees(math.atan2(direction[1], direction[0])):.0f} deg"
