"""Drive the simulated Panda: IK, OMPL transfers, straight Cartesian segments, gripper.

`ArmDriver` owns the robot side of one compiled world: Pinocchio kinematics, two
collision checkers (a 1 cm margin for free-space planning, a 2 mm one for the
configurations near contact: grasp, place, Cartesian segments) and the position
servos. Every motion is a time-parameterised stream of joint setpoints; the physics
alone decides what the hand and the objects do. All randomness (IK restarts, OMPL)
comes from the `np.random.Generator` given at construction. Time spent in IK, OMPL
and stepping is accumulated in `timings` (see `Timings`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.errors import GroundingError
from utamp_gym.robot.collision import CollisionChecker
from utamp_gym.robot.kinematics import HOME_Q, PandaKinematics
from utamp_gym.robot.motion import (
    PANDA_ACC_LIMITS,
    PANDA_VEL_LIMITS,
    plan_motion,
    time_parameterize,
)
from utamp_gym.robot.panda_mjcf import ARM_KP, ARM_KV, GRIPPER_FORCE, PandaIds

LEAD = ARM_KV[0] / ARM_KP[0]  # servo lag (s) cancelled by velocity feed-forward
FREE_SCALE = (0.8, 0.5)  # fraction of the Panda's velocity / acceleration limits, empty hand
HELD_SCALE = (0.5, 0.3)  # ... while carrying an object
LINE_STEP = 0.01  # m between IK waypoints of a Cartesian segment
MIN_GAP = 0.004  # m, closed fingers below this gap hold nothing
GUARD_EVERY = 4  # physics steps between two checks of a guarded motion's condition
#: a pinched wall thinner than `MIN_GAP` + `THIN_MARGIN` (a steel bowl's 1.2 mm rim) is held
#: when the gap stays at `THIN_FRACTION` of its width, at least `THIN_GAP`: fingers closed on
#: nothing meet at a gap of 0 (the Franka Hand reads its width to 0.1 mm)
THIN_MARGIN, THIN_FRACTION, THIN_GAP = 0.002, 0.5, 0.0004
#: a wall thinner than `PINCH_WIDTH` (a bowl's rim) is pinched with `PINCH_FORCE` N, as the
#: Franka Hand's grasp force is set per grasp: at the full 70 N the pads chatter on a thin
#: light wall and squirt it out (bowls of procedural v1: 25 of 40 lifted and placed at 70 N,
#: 39 of 40 at 30 N; 15 N lets the heavier ones slip)
PINCH_WIDTH, PINCH_FORCE = 0.007, 30.0
#: a steel-thin wall (below `STEEL_WIDTH`) whose expected weight has a moment about the pinch
#: of at most `LIGHT_MOMENT` N m is pinched with `LIGHT_PINCH_FORCE`: at 30 N the light steel
#: bowls and tumblers of procedural v1 chattered out of the pads (6 of their grasps slipped;
#: all held at 15 N), while saucepans with 0.35 N m and more slipped at 15-20 N
STEEL_WIDTH, LIGHT_MOMENT, LIGHT_PINCH_FORCE = 0.002, 0.25, 15.0
MAX_JOINT_JUMP = 0.25  # rad between consecutive Cartesian waypoints (no IK branch flips)
FINGERS_STILL = 2e-3  # m/s, fingers slower than this have stopped
SQUEEZE = 0.99  # fraction of the gripper's force limit: the fingers squeeze at full force


@dataclass
class Timings:
    """Seconds spent per phase of one macro action (wall clock except `sim_time_s`)."""

    ik_s: float = 0.0
    plan_s: float = 0.0
    sim_s: float = 0.0
    sim_time_s: float = 0.0

    def as_dict(self, wall_s: float) -> dict[str, float]:
        return {
            "ik_s": self.ik_s,
            "plan_s": self.plan_s,
            "sim_s": self.sim_s,
            "wall_s": wall_s,
            "sim_time_s": self.sim_time_s,
        }


@contextmanager
def allowing(
    checker: CollisionChecker,
    geoms1: Sequence[int],
    geoms2: Sequence[int],
    distance: float = -np.inf,
) -> Iterator[None]:
    """Within the block, contacts between `geoms1` and `geoms2` count only when closer than
    `distance` (m; -inf: never)."""
    saved = dict(checker.tolerance)
    for a in geoms1:
        for b in geoms2:
            checker.tolerance[(min(a, b), max(a, b))] = distance
    try:
        yield
    finally:
        checker.tolerance = saved


def ignoring(checker: CollisionChecker, geoms: Sequence[int]) -> AbstractContextManager[None]:
    """Within the block, contacts of the robot with `geoms` (e.g. the grasped object) do
    not count: the fingers are meant to touch it."""
    return allowing(checker, checker.ids.geom_ids.tolist(), geoms)


class ArmDriver:
    """Position-servo control of one Panda in a compiled MuJoCo model."""

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        ids: PandaIds,
        kin: PandaKinematics,
        rng: np.random.Generator,
        *,
        on_step: Callable[[], None] | None = None,
    ):
        self.model, self.data, self.ids, self.kin, self.rng = model, data, ids, kin, rng
        self.free = CollisionChecker(model, ids, margin=0.01, self_margin=0.002)
        self.near = CollisionChecker(model, ids, margin=0.002, self_margin=0.001)
        self.dt = float(model.opt.timestep)
        self.on_step = on_step  # called after every mj_step (e.g. a video recorder)
        #: maps the true qpos (a copy) to the one the robot believes (estimated object poses)
        self.belief: Callable[[np.ndarray], np.ndarray] | None = None
        self.timings = Timings()
        self.min_gap = MIN_GAP  # what `holds_something` asks of the gap (`expect_width`)

    # ------------------------------------------------------------ state
    def q(self) -> np.ndarray:
        return self.data.qpos[self.ids.arm_qpos_adr].copy()

    def gap(self) -> float:
        """Current finger gap (m)."""
        return float(self.data.qpos[self.ids.finger_qpos_adr].sum())

    def tcp(self) -> np.ndarray:
        """4x4 world pose of the TCP in the simulation."""
        out = np.eye(4)
        out[:3, :3] = self.data.site_xmat[self.ids.tcp_site_id].reshape(3, 3)
        out[:3, 3] = self.data.site_xpos[self.ids.tcp_site_id]
        return out

    def sync(self, checker: CollisionChecker, gap: float | None = None) -> CollisionChecker:
        """Give `checker` the world as the robot believes it (`belief`, else the simulated
        state), optionally with the fingers at `gap`."""
        qpos = self.data.qpos if self.belief is None else self.belief(self.data.qpos.copy())
        checker.set_world_state(qpos, self.data.mocap_pos, self.data.mocap_quat)
        if gap is not None:
            checker.data.qpos[self.ids.finger_qpos_adr] = gap / 2
        return checker

    # ------------------------------------------------------------ stepping
    def step(self, n: int) -> None:
        """Advance the physics `n` steps with the current controls."""
        t0 = time.perf_counter()
        if self.on_step is None:
            mujoco.mj_step(self.model, self.data, nstep=max(n, 0))
        else:
            for _ in range(n):
                mujoco.mj_step(self.model, self.data)
                self.on_step()
        self.timings.sim_s += time.perf_counter() - t0
        self.timings.sim_time_s += max(n, 0) * self.dt

    def track(self, setpoints: np.ndarray, until: Callable[[], bool] | None = None) -> bool:
        """Send one row of arm setpoints per physics step.

        With `until`, it is asked every `GUARD_EVERY` steps and tracking stops as soon as it
        answers True (a guarded motion); returns True if it did."""
        t0 = time.perf_counter()
        ctrl, act = self.data.ctrl, self.ids.arm_actuator_ids
        sent, stopped = 0, False
        for sent, q in enumerate(setpoints, start=1):
            ctrl[act] = q
            mujoco.mj_step(self.model, self.data)
            if self.on_step is not None:
                self.on_step()
            if until is not None and sent % GUARD_EVERY == 0 and until():
                stopped = True
                break
        self.timings.sim_s += time.perf_counter() - t0
        self.timings.sim_time_s += sent * self.dt
        return stopped

    def settle_arm(self, q_goal: np.ndarray, *, tol: float = 2e-3, max_s: float = 0.4) -> None:
        """Hold `q_goal` until the joints are within `tol` rad and nearly still."""
        self.data.ctrl[self.ids.arm_actuator_ids] = q_goal
        for _ in range(max(1, round(max_s / 0.02))):
            err = np.abs(self.q() - q_goal).max()
            speed = np.abs(self.data.qvel[self.ids.arm_dof_adr]).max()
            if err < tol and speed < 0.02:
                return
            self.step(10)

    def set_gripper(self, gap: float) -> None:
        self.data.ctrl[self.ids.gripper_actuator_id] = gap

    def close_gripper(self, *, min_s: float = 0.3, max_s: float = 0.8) -> float:
        """Squeeze (gap command 0, full gripper force) until the fingers stop; return the
        final gap (m).

        Done once the fingers are still at full force (they hold something: the squeeze is
        complete), checked every 10 ms; otherwise (closed on nothing) once they are still
        after `min_s`, or after `max_s`.
        """
        self.set_gripper(0.0)
        force = self.model.actuator_forcerange[self.ids.gripper_actuator_id, 1]
        t, every = 0.0, max(1, round(0.01 / self.dt))
        while t < max_s - 1e-9:
            self.step(every)
            t += every * self.dt
            still = np.abs(self.data.qvel[self.ids.finger_dof_adr]).max() < FINGERS_STILL
            squeezing = (
                abs(self.data.actuator_force[self.ids.gripper_actuator_id]) >= SQUEEZE * force
            )
            if still and (squeezing or t >= min_s - 1e-9):
                break
        return self.gap()

    def holds_something(self) -> bool:
        """True if the closed fingers are held apart by something."""
        return self.gap() > self.min_gap

    def expect_width(self, width: float, moment: float | None = None) -> None:
        """The fingers are about to close on a member `width` m across: a thin wall (below
        `MIN_GAP` + `THIN_MARGIN`) is held at a smaller gap than `MIN_GAP`, one narrower
        than `PINCH_WIDTH` is squeezed with `PINCH_FORCE` (else the full `GRIPPER_FORCE`),
        one below `STEEL_WIDTH` whose expected weight's `moment` about the grasp is at most
        `LIGHT_MOMENT` with `LIGHT_PINCH_FORCE`."""
        thin = width < MIN_GAP + THIN_MARGIN
        self.min_gap = max(THIN_GAP, THIN_FRACTION * width) if thin else MIN_GAP
        force = PINCH_FORCE if width < PINCH_WIDTH else GRIPPER_FORCE
        if width < STEEL_WIDTH and moment is not None and moment <= LIGHT_MOMENT:
            force = LIGHT_PINCH_FORCE
        self.model.actuator_forcerange[self.ids.gripper_actuator_id] = (-force, force)

    def open_gripper(self, gap: float, *, clear: float | None = None, max_s: float = 0.6) -> None:
        """Move the fingers to `gap`; wait until they are there or, with `clear`, only
        until they opened that far beyond the current gap (enough to let go)."""
        target = gap if clear is None else min(gap, self.gap() + clear)
        self.set_gripper(gap)
        for _ in range(round(max_s / 0.02)):
            if abs(self.gap() - target) < 1.5e-3 or (clear is not None and self.gap() > target):
                break
            self.step(10)

    # ------------------------------------------------------------ IK and paths
    def seed_for(self, target: np.ndarray) -> np.ndarray:
        """The ready pose turned towards `target` with the wrist pre-rotated to its yaw.

        A natural elbow-up start for IK (at the ready pose, TCP yaw = q1 - (q7 - q7_home)).
        """
        q = np.array(HOME_Q)
        q[0] = np.arctan2(target[1, 3], target[0, 3])
        yaw = np.arctan2(target[1, 0], target[0, 0])
        q[6] = HOME_Q[6] + (q[0] - yaw + np.pi) % (2 * np.pi) - np.pi
        return np.clip(q, self.kin.lower, self.kin.upper)

    def ik_solutions(
        self,
        target: np.ndarray,
        accept: Callable[[np.ndarray], bool] | None,
        *,
        restarts: int = 10,
    ) -> Iterator[np.ndarray]:
        """Accepted IK solutions for `target`: from `seed_for`, the current and the ready
        configuration, then from `restarts` random starts (lazily, in that order)."""
        seeds = [self.seed_for(target), self.q(), np.array(HOME_Q)]
        for k in range(len(seeds) + restarts):
            t0 = time.perf_counter()
            seed = seeds[k] if k < len(seeds) else self.kin.random_q(self.rng)
            res = self.kin.ik(target, seed, self.rng, accept=accept, max_attempts=1)
            self.timings.ik_s += time.perf_counter() - t0
            if res.success:
                yield res.q

    def line(
        self,
        q_start: np.ndarray,
        start: np.ndarray,
        offset: np.ndarray,
        valid: Callable[[np.ndarray], bool],
        *,
        what: str,
    ) -> LinePath:
        """Joint waypoints moving the TCP from `start` (4x4) by `offset` (m), orientation fixed.

        Each waypoint is solved from the previous one (a step that turns a joint more than
        `MAX_JOINT_JUMP` is subdivided) and must be `valid`; raises `GroundingError`
        naming `what` if the line leaves the arm's reach or collides.
        """
        offset = np.asarray(offset, dtype=float)
        length = float(np.linalg.norm(offset))
        n = max(1, int(np.ceil(length / LINE_STEP)))
        knots, path = [0.0], [np.asarray(q_start, dtype=float)]
        # segments (from, to, depth) still to solve, the next on top; a stack rather than a
        # recursive closure, whose reference cycle would keep this driver (and its world)
        # alive until Python's next full garbage collection
        todo = [(length * (k - 1) / n, length * k / n, 0) for k in range(n, 0, -1)]
        t0 = time.perf_counter()
        try:
            while length > 0 and todo:
                s_from, s_to, depth = todo.pop()
                target = start.copy()
                target[:3, 3] = start[:3, 3] + offset * (s_to / length)
                res = self.kin.ik(target, path[-1], self.rng, max_attempts=1)
                if res.success and np.abs(res.q - path[-1]).max() <= MAX_JOINT_JUMP:
                    if not valid(res.q):
                        raise GroundingError(f"{what} would collide ({self._why(res.q)})")
                    knots.append(s_to)
                    path.append(res.q)
                elif depth < 3:  # halve the step: the first half is solved first
                    mid = (s_from + s_to) / 2
                    todo += [(mid, s_to, depth + 1), (s_from, mid, depth + 1)]
                else:
                    raise GroundingError(f"IK infeasible: {what} leaves the arm's reach")
        finally:
            self.timings.ik_s += time.perf_counter() - t0
        return LinePath(np.array(knots), np.array(path))

    def _why(self, q: np.ndarray) -> str:
        contacts = self.near.contacts(q)
        return self.near.describe(contacts) if contacts else "joint limits"

    def move_line(
        self,
        line: LinePath,
        speed: float,
        acc: float,
        *,
        until: Callable[[], bool] | None = None,
    ) -> bool:
        """Follow a Cartesian line at up to `speed` m/s (trapezoidal, joint speeds capped).

        Guarded with `until` (asked every `GUARD_EVERY` physics steps): the arm stops where it
        is as soon as it answers True, and holds that pose. Returns True if it stopped early.
        """
        if line.length > 0:
            vel = PANDA_VEL_LIMITS * FREE_SCALE[0]
            if self.track(line_setpoints(line, speed, acc, vel, self.dt), until):
                self.settle_arm(self.q())
                return True
        self.settle_arm(line.q[-1])
        return False

    def transfer(
        self,
        q_goal: np.ndarray,
        *,
        held: tuple[int, np.ndarray] | None = None,
        turned: np.ndarray | None = None,
        what: str = "",
    ) -> None:
        """Collision-free joint motion (OMPL if the straight line is blocked) to `q_goal`.

        `held` = (body id, tcp_T_obj) carries an object in the collision model, checked at
        `turned` (tcp_T_obj) as well if given: where it may turn in the hand on the way.
        Raises `GroundingError` ("OMPL infeasible: <what>: ...") if no path is found.
        """
        checker = self.sync(self.free)
        if held is not None:
            checker.attach(held[0], held[1], () if turned is None else (turned,))
        t0 = time.perf_counter()
        try:
            plan = plan_motion(checker, self.q(), q_goal, self.rng, timeout=1.5)
        except GroundingError as exc:
            raise GroundingError(f"OMPL infeasible: {what or 'transfer'}: {exc}") from None
        finally:
            checker.detach()
            self.timings.plan_s += time.perf_counter() - t0
        vel, acc = HELD_SCALE if held is not None else FREE_SCALE
        setpoints = time_parameterize(
            plan.waypoints, PANDA_VEL_LIMITS * vel, PANDA_ACC_LIMITS * acc, self.dt, lead=LEAD
        )
        self.track(setpoints)
        self.settle_arm(q_goal)


@dataclass(frozen=True)
class LinePath:
    """Joint waypoints `q` (N, 7) of a straight TCP line at arc lengths `s` (N,), metres."""

    s: np.ndarray
    q: np.ndarray

    @property
    def length(self) -> float:
        return float(self.s[-1])

    @property
    def end(self) -> np.ndarray:
        return self.q[-1]

    def reversed(self) -> LinePath:
        return LinePath(self.length - self.s[::-1], self.q[::-1])

    def split(self, at: float) -> tuple[LinePath, LinePath]:
        """(the line up to its first waypoint at or beyond `at` m, the rest from there)."""
        k = max(1, min(int(np.searchsorted(self.s, at - 1e-9)), len(self.s) - 1))
        return LinePath(self.s[: k + 1], self.q[: k + 1]), LinePath(
            self.s[k:] - self.s[k], self.q[k:]
        )


def line_setpoints(
    line: LinePath, speed: float, acc: float, joint_vel: np.ndarray, dt: float
) -> np.ndarray:
    """Setpoints along a line with a trapezoidal arc-length profile and velocity feed-forward.

    The path speed is lowered where needed so no joint exceeds `joint_vel`.
    """
    knots, path, length = line.s, line.q, line.length
    dq = np.diff(path, axis=0) / np.maximum(np.diff(knots), 1e-12)[:, None]
    v = min(speed, float(np.min(joint_vel / np.maximum(np.abs(dq).max(axis=0), 1e-9))))
    v = min(v, float(np.sqrt(length * acc)))
    t_acc = v / acc
    duration = 2 * t_acc + max(0.0, (length - v * t_acc) / v)
    t = np.minimum(np.arange(1, int(np.ceil(duration / dt)) + 1) * dt, duration)
    s = np.where(
        t < t_acc,
        0.5 * acc * t**2,
        np.where(
            t < duration - t_acc,
            0.5 * acc * t_acc**2 + v * (t - t_acc),
            length - 0.5 * acc * (duration - t) ** 2,
        ),
    )
    s = np.clip(s, 0.0, length)
    sdot = np.where(t < t_acc, acc * t, np.where(t < duration - t_acc, v, acc * (duration - t)))
    q = np.column_stack([np.interp(s, knots, path[:, j]) for j in range(path.shape[1])])
    idx = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, len(dq) - 1)
    return q + LEAD * sdot[:, None] * dq[idx]
