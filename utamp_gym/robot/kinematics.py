"""Panda arm kinematics with Pinocchio: FK of the TCP frame and damped-least-squares IK.

The model is the example-robot-data URDF reduced to the 7 arm joints (fingers
locked open), so it matches `panda_mjcf.add_panda` joint for joint. Poses are
4x4 homogeneous matrices in the robot base frame, or (position, quaternion wxyz).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from utamp_gym.errors import AssetError, GroundingError
from utamp_gym.robot.assets import PandaAssets, panda_assets

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
TCP_FRAME = "panda_hand_tcp"
# SRDF "default" group state (the usual ready pose).
HOME_Q = (0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398)
#: m from the base's axis: the TCP pointing straight down reaches 0.785-0.807 m out at 0-30 cm
#: above the table, on every bearing (`tests/test_robot_kinematics.py` checks this arm model
#: reaches this far and not 3 cm farther); a member beyond it cannot be grasped from above
TOP_DOWN_REACH = 0.78

PoseLike = np.ndarray | tuple[np.ndarray, np.ndarray]


def quat_wxyz_to_matrix(quat: np.ndarray) -> np.ndarray:
    """3x3 rotation matrix of a (not necessarily unit) quaternion given as w, x, y, z."""
    w, x, y, z = (float(v) for v in quat)
    return pin.Quaternion(w, x, y, z).normalized().matrix()


def matrix_to_quat_wxyz(rot: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z, with w >= 0) of a 3x3 rotation matrix."""
    x, y, z, w = pin.Quaternion(np.asarray(rot, dtype=float)).coeffs()
    quat = np.array([w, x, y, z])
    return -quat if w < 0 else quat


def pose_matrix(pos: np.ndarray, quat_wxyz: np.ndarray) -> np.ndarray:
    """4x4 homogeneous matrix from a position and a wxyz quaternion."""
    out = np.eye(4)
    out[:3, :3] = quat_wxyz_to_matrix(quat_wxyz)
    out[:3, 3] = pos
    return out


def as_matrix(pose: PoseLike) -> np.ndarray:
    """Accept a 4x4 matrix or a (pos, quat_wxyz) pair; return a 4x4 matrix."""
    if isinstance(pose, tuple):
        return pose_matrix(np.asarray(pose[0], float), np.asarray(pose[1], float))
    mat = np.asarray(pose, dtype=float)
    if mat.shape != (4, 4):
        raise GroundingError(f"pose must be a 4x4 matrix or (pos, quat_wxyz), got {mat.shape}")
    return mat


@dataclass(frozen=True)
class IKResult:
    """Outcome of `PandaKinematics.ik`. `q` is the best configuration found even on failure."""

    q: np.ndarray
    success: bool
    pos_error: float  # m
    rot_error: float  # rad
    iterations: int  # over all attempts
    attempts: int
    rejected: int  # converged solutions refused by `accept`
    time: float  # s


class PandaKinematics:
    """Pinocchio model of the 7-DoF arm with the TCP frame `panda_hand_tcp`."""

    def __init__(self, assets: PandaAssets | None = None, finger_opening: float = 0.04):
        assets = assets or panda_assets()
        try:
            full = pin.buildModelFromUrdf(str(assets.urdf))
        except (RuntimeError, ValueError) as exc:
            raise AssetError(f"Pinocchio could not load {assets.urdf}: {exc}") from exc
        q_ref = pin.neutral(full)
        lock = []
        for name in FINGER_JOINTS:
            jid = full.getJointId(name)
            q_ref[full.joints[jid].idx_q] = finger_opening
            lock.append(jid)
        self.model = pin.buildReducedModel(full, lock, q_ref)
        self.data = self.model.createData()
        self.tcp_frame = self.model.getFrameId(TCP_FRAME)
        self.lower = np.array(self.model.lowerPositionLimit, dtype=float)
        self.upper = np.array(self.model.upperPositionLimit, dtype=float)
        self.velocity_limit = np.array(self.model.velocityLimit, dtype=float)
        self.effort_limit = np.array(self.model.effortLimit, dtype=float)
        self.joint_names = ARM_JOINTS

    # ------------------------------------------------------------------ FK
    def frame_pose(self, q: np.ndarray, frame: str = TCP_FRAME) -> np.ndarray:
        """4x4 pose of a URDF frame (link or joint name) in the base frame."""
        fid = self.model.getFrameId(frame)
        if fid >= self.model.nframes:
            raise GroundingError(f"unknown Pinocchio frame '{frame}'")
        pin.forwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return pin.updateFramePlacement(self.model, self.data, fid).homogeneous

    def fk(self, q: np.ndarray) -> np.ndarray:
        """4x4 TCP pose in the base frame."""
        return self.frame_pose(q)

    def fk_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TCP (position, quaternion wxyz) in the base frame."""
        mat = self.fk(q)
        return mat[:3, 3].copy(), matrix_to_quat_wxyz(mat[:3, :3])

    def within_limits(self, q: np.ndarray, tol: float = 1e-9) -> bool:
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def random_q(self, rng: np.random.Generator, margin: float = 0.0) -> np.ndarray:
        """Uniform configuration inside the joint limits shrunk by `margin` rad."""
        return rng.uniform(self.lower + margin, self.upper - margin)

    # ------------------------------------------------------------------ IK
    def ik(
        self,
        target: PoseLike,
        q_seed: np.ndarray,
        rng: np.random.Generator,
        *,
        accept: Callable[[np.ndarray], bool] | None = None,
        max_attempts: int = 20,
        max_iters: int = 150,
        pos_tol: float = 1e-4,
        rot_tol: float = 1e-3,
        timeout: float | None = None,
    ) -> IKResult:
        """Solve for the arm configuration whose TCP pose equals `target`.

        Damped least squares on the log6 error in the TCP frame; joints that hit a
        limit are clamped and dropped from the step. The first attempt starts at
        `q_seed`, later ones at uniform samples from `rng`. A converged solution is
        returned only if `accept(q)` (e.g. a collision check) agrees.
        """
        t0 = time.perf_counter()
        o_m_des = pin.SE3(as_matrix(target))
        q_start = np.clip(np.asarray(q_seed, dtype=float), self.lower, self.upper)
        best = (np.inf, q_start, np.inf, np.inf)
        iterations = rejected = attempts = 0
        for attempt in range(max_attempts):
            if timeout is not None and attempt > 0 and time.perf_counter() - t0 > timeout:
                break
            attempts += 1
            q0 = q_start if attempt == 0 else self.random_q(rng)
            q, pos_err, rot_err, iters = self._solve_from(o_m_des, q0, max_iters, pos_tol, rot_tol)
            iterations += iters
            converged = pos_err <= pos_tol and rot_err <= rot_tol
            if converged and accept is not None and not accept(q):
                rejected += 1
                continue
            if converged:
                return IKResult(
                    q,
                    True,
                    pos_err,
                    rot_err,
                    iterations,
                    attempts,
                    rejected,
                    time.perf_counter() - t0,
                )
            score = pos_err + 0.1 * rot_err
            if score < best[0]:
                best = (score, q, pos_err, rot_err)
        _, q, pos_err, rot_err = best
        return IKResult(
            q, False, pos_err, rot_err, iterations, attempts, rejected, time.perf_counter() - t0
        )

    def _solve_from(
        self, o_m_des: pin.SE3, q: np.ndarray, max_iters: int, pos_tol: float, rot_tol: float
    ) -> tuple[np.ndarray, float, float, int]:
        model, data, fid = self.model, self.data, self.tcp_frame
        eye6 = np.eye(6)
        q = q.copy()
        prev = np.inf
        stall = 0
        pos_err = rot_err = np.inf
        for it in range(1, max_iters + 1):
            pin.forwardKinematics(model, data, q)
            i_m_d = pin.updateFramePlacement(model, data, fid).actInv(o_m_des)
            err = pin.log6(i_m_d).vector
            pos_err = float(np.linalg.norm(i_m_d.translation))
            rot_err = float(np.linalg.norm(err[3:]))
            if pos_err <= pos_tol and rot_err <= rot_tol:
                return q, pos_err, rot_err, it
            # Stop early when progress stalls (local minimum or stuck at a limit).
            total = pos_err + 0.2 * rot_err
            stall = stall + 1 if total > 0.995 * prev else 0
            prev = min(prev, total)
            if stall >= 10:
                return q, pos_err, rot_err, it
            jac = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            jac = pin.Jlog6(i_m_d.inverse()) @ jac
            lam = 1e-4 + 1e-2 * float(err @ err)
            free = np.ones(q.size, dtype=bool)
            for _ in range(2):  # drop joints pushed against a limit, then re-solve
                jf = jac[:, free]
                dq = np.zeros_like(q)
                dq[free] = jf.T @ np.linalg.solve(jf @ jf.T + lam * eye6, err)
                scale = 0.5 / max(0.5, float(np.max(np.abs(dq))))  # cap each step at 0.5 rad
                q_new = q + scale * dq
                blocked = ((q_new < self.lower) & (dq < 0)) | ((q_new > self.upper) & (dq > 0))
                if not blocked.any() or not free[~blocked].any():
                    break
                free &= ~blocked
            q = np.clip(q_new, self.lower, self.upper)
        return q, pos_err, rot_err, max_iters
