"""Replay a macro plan's joint trajectories through the low-level dm_control interface.

`record_plan` executes a plan with the physics executor (`MujocoBackend`: IK, OMPL, position
servos) and records, after every physics step, the commands it sent to the 8 servos (7 arm
joint targets, the gripper gap). `JointTrajectory.at_rate` averages them over each control
step, and `ReplayPolicy` sends them, one row per control step, as the actions of a
`utamp_gym.dm.load` environment. The replay is open loop: it reproduces the executor's
motion only from the same initial state, so record and replay without initial pose noise
(``pos_noise=0, yaw_noise_deg=0`` for `load`; `record_plan` uses none).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import dm_env
import numpy as np

from utamp_gym.errors import SimulationError
from utamp_gym.scene.model import Scene
from utamp_gym.sim.backend import MujocoBackend
from utamp_gym.suites import resolve_scene

HOLD_S = 1.0  # s the last command is held after the plan (the scene settles)


@dataclass(frozen=True)
class JointTrajectory:
    """Servo commands (n, 8): 7 arm joint targets (rad) and the gripper gap (m), one row per
    `dt` seconds, from the state after the scene settled."""

    commands: np.ndarray
    dt: float
    #: per row, the index in the plan of the macro action that sent it (-1: the final hold)
    steps: np.ndarray | None = None

    @property
    def duration(self) -> float:
        return len(self.commands) * self.dt

    def at_rate(self, control_timestep: float) -> JointTrajectory:
        """The commands averaged over each control step (a zero-order hold replays them)."""
        n = max(1, round(control_timestep / self.dt))
        rows = -(-len(self.commands) // n)
        pad = rows * n - len(self.commands)
        padded = np.concatenate([self.commands, np.repeat(self.commands[-1:], pad, 0)])
        steps = None
        if self.steps is not None:  # a control step's label: the one of its first row
            steps = np.concatenate([self.steps, np.full(pad, -1)]).reshape(rows, n)[:, 0]
        return JointTrajectory(padded.reshape(rows, n, -1).mean(axis=1), self.dt * n, steps)


def record_plan(
    scene: Scene | str, plan: Sequence[str], seed: int = 0, *, hold_s: float = HOLD_S
) -> JointTrajectory:
    """Execute `plan` in physics (no initial pose noise, exact pose estimates) and record
    the servo commands of every physics step; raises `SimulationError` if a step fails."""
    if isinstance(scene, str):
        scene = resolve_scene(scene)
    backend = MujocoBackend(pos_noise=0.0, yaw_noise_deg=0.0, pose_noise=0.0)
    rows: list[np.ndarray] = []
    try:
        backend.reset(scene, np.random.default_rng(seed))
        ids = backend.state.arm.ids
        act = [*ids.arm_actuator_ids.tolist(), ids.gripper_actuator_id]
        dt = float(backend.model.opt.timestep)
        data = backend.data
        backend.watch(lambda: rows.append(data.ctrl[act].copy()), dt)
        ends = []
        for i, action in enumerate(plan):
            result = backend.execute(action)
            if not result.success:
                raise SimulationError(f"step {i} {action} failed: {result.reason}")
            ends.append(len(rows))
        last = data.ctrl[act].copy()
    finally:
        backend.close()
    hold = np.repeat(last[None], round(hold_s / dt), axis=0)
    steps = np.concatenate([np.searchsorted(ends, np.arange(len(rows)), side="right"),
                            np.full(len(hold), -1)])  # fmt: skip
    commands = np.concatenate([np.array(rows).reshape(-1, len(act)), hold])
    return JointTrajectory(commands, dt, steps)


class ReplayPolicy:
    """A dm_control policy (``policy(time_step) -> action``) sending a trajectory's commands
    one row per control step, then holding the last; restarts at every FIRST step."""

    def __init__(self, trajectory: JointTrajectory, control_timestep: float) -> None:
        self.trajectory = trajectory.at_rate(control_timestep)
        self._k = 0

    def reset(self) -> None:
        """Start from the first command (dm_control's viewer calls this on restart)."""
        self._k = 0

    def __call__(self, time_step: dm_env.TimeStep) -> np.ndarray:
        if time_step.first():
            self._k = 0
        commands = self.trajectory.commands
        action = commands[min(self._k, len(commands) - 1)]
        self._k += 1
        return action.copy()

    @property
    def n_steps(self) -> int:
        """Control steps until the last command."""
        return len(self.trajectory.commands)
