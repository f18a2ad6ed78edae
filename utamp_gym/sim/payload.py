"""Payload from joint torques: what the hand carries, measured the way the Panda does it.

The model. The arm compensates its own gravity through its actuators (`panda_mjcf`:
MuJoCo's `actuatorgravcomp`), so each arm joint's torque tau_J (`qfrc_actuator`: servo
plus compensation) is clamped to the Panda's joint torque limit (87 N·m joints 1-4,
12 N·m joints 5-7, from the URDF). A load in the hand adds

    tau_ext = tau_J - g(q) = -J(q)^T F,

where g(q) is the robot's model of its own weight (links, hand and fingers:
`qfrc_gravcomp`), J the 6x7 Jacobian of the TCP site (`mj_jacSite`) and F the wrench
(force, moment about the TCP, world frame) the load exerts on the hand. Least squares
gives F; the load's mass is -F_z / g and its lever arm ``|M_horizontal| / |F_z|``. The
estimate is quasi-static, like the Franka's own payload estimation: it is averaged while
the arm holds a pose, where the arm's inertial and Coriolis torques vanish. The catalogue
mass is never read: the torques see only what physics puts on the hand (a tray whose far
edge still rests on the table weighs partly on the table).

The hand is overloaded when the estimated load exceeds the Panda's rated payload
(`RATED_PAYLOAD_KG`, 3 kg, Franka Emika datasheet), or when a joint's torque stays at its
limit while holding (saturated: the arm cannot hold the pose at all, and the estimate is
only a lower bound). Failure reasons name the object and the measured load and contain
the word "payload".
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.robot.panda_mjcf import PandaIds
from utamp_gym.sim.control import ArmDriver

RATED_PAYLOAD_KG = 3.0  # Franka Emika Panda, rated payload
SATURATED = 0.995  # |tau_J| at this fraction of the joint's limit counts as saturated
SATURATED_SHARE = 0.5  # ... for at least this share of the holding window
HOLD_S = 0.15  # s, the holding window after a lift


@dataclass(frozen=True)
class LoadReading:
    """The load on the hand estimated from the arm's joint torques (see the module doc)."""

    force: np.ndarray  # (3,) N, the load's force on the hand, world frame
    moment: np.ndarray  # (3,) N·m, its moment about the TCP
    saturated: tuple[int, ...]  # arm joints (1-7) held at their torque limit
    limits: np.ndarray  # (7,) N·m, the joints' torque limits
    gravity: float  # m/s^2

    @property
    def mass_kg(self) -> float:
        """Mass the hand bears (kg): the downward force over g."""
        return max(0.0, -float(self.force[2]) / self.gravity)

    @property
    def lever_m(self) -> float:
        """Horizontal distance (m) from the TCP to the line of the load's weight."""
        return float(np.linalg.norm(self.moment[:2])) / max(abs(float(self.force[2])), 1e-9)

    @property
    def overloaded(self) -> bool:
        return bool(self.saturated) or self.mass_kg > RATED_PAYLOAD_KG

    def describe(self) -> str:
        """'2.1 kg (21 N)': the measured load (its weight and the whole force), for reasons."""
        return f"{self.mass_kg:.1f} kg ({np.linalg.norm(self.force):.0f} N)"


def joint_torque_limits(model: mujoco.MjModel, ids: PandaIds) -> np.ndarray:
    """(7,) N·m: the arm joints' torque limits (`jnt_actfrcrange`)."""
    return model.jnt_actfrcrange[ids.arm_joint_ids, 1].copy()


def external_torques(data: mujoco.MjData, ids: PandaIds) -> np.ndarray:
    """(7,) N·m: measured joint torques minus the arm's own gravity, tau_J - g(q)."""
    return data.qfrc_actuator[ids.arm_dof_adr] - data.qfrc_gravcomp[ids.arm_dof_adr]


def external_torques_moving(
    model: mujoco.MjModel, data: mujoco.MjData, ids: PandaIds
) -> np.ndarray:
    """(7,) N·m: the external torques while the arm moves, from the robot's dynamic model
    (as the Panda estimates its external wrench in motion): tau_J + tau_friction -
    (M(q) qdd + c(q, qd) + g(q)), the terms of the last physics step."""
    m_qacc = np.zeros(model.nv)
    mujoco.mj_mulM(model, data, m_qacc, data.qacc)
    adr = ids.arm_dof_adr
    return data.qfrc_actuator[adr] + data.qfrc_passive[adr] - data.qfrc_bias[adr] - m_qacc[adr]


def hand_force_now(arm: ArmDriver) -> np.ndarray:
    """(3,) N: the load's force on the hand at this instant, moving or not (world frame)."""
    tau = external_torques_moving(arm.model, arm.data, arm.ids)
    return hand_wrench(arm.model, arm.data, arm.ids, tau)[:3]


def hand_wrench(
    model: mujoco.MjModel, data: mujoco.MjData, ids: PandaIds, tau_ext: np.ndarray
) -> np.ndarray:
    """(6,) force (N) and moment about the TCP (N·m) on the hand explaining `tau_ext`."""
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_jacSite(model, data, jacp, jacr, ids.tcp_site_id)
    jac = np.vstack([jacp, jacr])[:, ids.arm_dof_adr]  # (6, 7)
    wrench, *_ = np.linalg.lstsq(jac.T, -np.asarray(tau_ext, dtype=float), rcond=None)
    return wrench


def hold_and_measure(arm: ArmDriver, seconds: float = HOLD_S) -> LoadReading:
    """Step the physics `seconds` with the current setpoints and estimate the hand's load.

    The external torques are averaged over the second half of the window (after the
    settling transient) and turned into a wrench with the Jacobian at its end (the arm
    holds still); a joint counts as saturated if it is at its limit for `SATURATED_SHARE`
    of the window (a single contact impulse does not).
    """
    model, data, ids = arm.model, arm.data, arm.ids
    limits = joint_torque_limits(model, ids)
    n = max(2, round(seconds / arm.dt))
    at_limit = np.zeros(len(limits))
    tau_ext = np.zeros(len(limits))
    for k in range(n):
        arm.step(1)
        at_limit += np.abs(data.qfrc_actuator[ids.arm_dof_adr]) >= SATURATED * limits
        if k >= n // 2:
            tau_ext += external_torques(data, ids)
    wrench = hand_wrench(model, data, ids, tau_ext / (n - n // 2))
    saturated = tuple(int(j) + 1 for j in np.flatnonzero(at_limit >= SATURATED_SHARE * n))
    gravity = float(np.linalg.norm(model.opt.gravity))
    return LoadReading(wrench[:3], wrench[3:], saturated, limits, gravity)


def payload_failure(obj: str, reading: LoadReading, *, while_: str) -> str | None:
    """The failure reason if `reading` overloads the Panda while `while_` `obj`, else None."""
    if reading.saturated:
        joints = " and ".join(
            f"joint {j} at its {reading.limits[j - 1]:.0f} N·m limit" for j in reading.saturated
        )
        return (
            f"{obj} exceeds the Panda's payload while {while_} it: the torque of {joints} "
            f"cannot hold it (measured load at least {reading.describe()})"
        )
    if reading.mass_kg > RATED_PAYLOAD_KG:
        return (
            f"{obj} exceeds the Panda's {RATED_PAYLOAD_KG:g} kg payload while {while_} it: "
            f"the joint torques measure {reading.describe()} at the hand"
        )
    return None
