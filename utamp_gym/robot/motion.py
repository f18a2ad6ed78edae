"""Joint-space motion planning (OMPL RRTConnect) and trajectory timing for the Panda arm.

`plan_motion` checks the straight line first, then runs RRTConnect with a
`CollisionChecker` as validity checker, simplifies and returns a dense waypoint path.
OMPL's random numbers are seeded from the caller's `np.random.Generator` on every call
(OMPL 2.0.1 exposes only a global seed, which seeds every OMPL RNG created afterwards).
RRTConnect's limit is counted in collision checks, not seconds (`timeout` / `CHECK_S`, what
that many seconds allow on an idle machine), so the same Generator state gives the same path,
or the same failure, however loaded the machine is; a wall-clock limit of
`SAFETY_FACTOR` x `timeout` only guards against a pathological check.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from utamp_gym.errors import GroundingError
from utamp_gym.robot.collision import CollisionChecker

# Franka Panda datasheet limits (rad/s, rad/s^2); callers usually scale them down.
PANDA_VEL_LIMITS = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
PANDA_ACC_LIMITS = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
PANDA_VEL_LIMITS.flags.writeable = False
PANDA_ACC_LIMITS.flags.writeable = False
LIMIT_SLACK = 0.02  # rad a start/goal may lie outside a joint limit (clipped back in)
CHECK_S = 60e-6  # s per collision check on an idle machine (a Panda in a kitchen scene)
SAFETY_FACTOR = 20.0  # wall-clock limit of RRTConnect, in multiples of its nominal timeout


@dataclass(frozen=True)
class MotionPlan:
    """A collision-checked joint path from start to goal."""

    waypoints: np.ndarray  # (N, 7) dense path, consecutive points <= waypoint_step apart
    vertices: np.ndarray  # (M, 7) simplified path corners (start ... goal)
    direct: bool  # True if the straight line was valid (no sampling planner used)
    plan_time: float  # s, RRTConnect
    simplify_time: float  # s
    checks: int  # state validity checks performed


def interpolate_path(path: np.ndarray, step: float) -> np.ndarray:
    """Insert points so no joint moves more than `step` rad between consecutive rows."""
    path = np.asarray(path, dtype=float)
    out = [path[:1]]
    for a, b in itertools.pairwise(path):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        t = np.arange(1, n + 1)[:, None] / n
        out.append(a + t * (b - a))
    return np.concatenate(out)


def dense_check(
    path: np.ndarray, checker: CollisionChecker | Callable[[np.ndarray], bool], resolution: float
) -> int | None:
    """Index of the first waypoint whose approach (from the previous one) is invalid.

    Every motion is re-checked at `resolution` rad; returns 0 if the first waypoint
    itself is invalid and None if the whole path is valid.
    """
    valid = checker.is_valid if isinstance(checker, CollisionChecker) else checker
    path = np.asarray(path, dtype=float)
    if not valid(path[0]):
        return 0
    for i in range(1, len(path)):
        for q in interpolate_path(path[i - 1 : i + 1], resolution)[1:]:
            if not valid(q):
                return i
    return None


def seed_ompl(rng: np.random.Generator) -> int:
    """Seed OMPL's global RNG from `rng` (silencing its 'already started' notice)."""
    seed = int(rng.integers(1, 2**31 - 1))
    with _ompl_log_level(ou.LOG_NONE):
        ou.RNG.setSeed(seed)
    return seed


def plan_motion(
    checker: CollisionChecker,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    rng: np.random.Generator,
    *,
    timeout: float = 2.0,
    simplify_time: float = 5.0,
    check_resolution: float = 0.02,
    waypoint_step: float = 0.02,
    max_endpoint_penetration: float = 0.01,
) -> MotionPlan:
    """Plan a collision-free joint path; raises `GroundingError` if there is none in time.

    The checker must already hold the current world state (`sync`) and any held
    object (`attach`). Start and goal up to `LIMIT_SLACK` outside a joint limit are
    clipped into it. Contacts already present at the start or goal within the
    margin are tolerated as long as they do not get deeper (`tolerating`).
    """
    q_start = _within_limits(checker, q_start, "start")
    q_goal = _within_limits(checker, q_goal, "goal")
    for label, q in (("start", q_start), ("goal", q_goal)):
        deep = [
            c for c in checker.contacts(q, tolerate=False) if c.dist < -max_endpoint_penetration
        ]
        if deep:
            raise GroundingError(f"{label} configuration in collision: {checker.describe(deep)}")
    checks0 = checker.checks
    with checker.tolerating(q_start, q_goal):
        line = interpolate_path(np.stack([q_start, q_goal]), check_resolution)
        if all(checker.is_valid(q) for q in line):
            return MotionPlan(
                interpolate_path(np.stack([q_start, q_goal]), waypoint_step),
                np.stack([q_start, q_goal]),
                True,
                0.0,
                0.0,
                checker.checks - checks0,
            )
        vertices, t_plan, t_simp = _rrt_connect(
            checker, q_start, q_goal, rng, timeout, simplify_time, check_resolution
        )
    vertices[0], vertices[-1] = q_start, q_goal
    return MotionPlan(
        interpolate_path(vertices, waypoint_step),
        vertices,
        False,
        t_plan,
        t_simp,
        checker.checks - checks0,
    )


def _within_limits(checker: CollisionChecker, q: np.ndarray, label: str) -> np.ndarray:
    """`q` clipped into the joint limits (a simulated joint may overshoot slightly)."""
    q = np.asarray(q, dtype=float)
    if q.shape != (7,):
        raise GroundingError(f"{label} configuration must have 7 values, got {q.shape}")
    if np.any(q < checker.lower - LIMIT_SLACK) or np.any(q > checker.upper + LIMIT_SLACK):
        raise GroundingError(f"{label} configuration {np.round(q, 3)} violates joint limits")
    return np.clip(q, checker.lower, checker.upper)


def _rrt_connect(
    checker: CollisionChecker,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    rng: np.random.Generator,
    timeout: float,
    simplify_time: float,
    resolution: float,
) -> tuple[np.ndarray, float, float]:
    seed_ompl(rng)  # before any OMPL object (and its RNG) is created
    space = ob.RealVectorStateSpace(7)
    bounds = ob.RealVectorBounds(7)
    for i in range(7):
        bounds.setLow(i, float(checker.lower[i]))
        bounds.setHigh(i, float(checker.upper[i]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    setup.setStateValidityChecker(lambda s: checker.is_valid(np.array([s[i] for i in range(7)])))
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(resolution / space.getMaximumExtent())
    start, goal = space.allocState(), space.allocState()
    for i in range(7):
        start[i], goal[i] = float(q_start[i]), float(q_goal[i])
    setup.setStartAndGoalStates(start, goal)
    setup.setPlanner(og.RRTConnect(info))
    t0 = time.perf_counter()
    budget, checks0 = round(timeout / CHECK_S), checker.checks
    wall_end = t0 + SAFETY_FACTOR * timeout

    def used_up() -> bool:  # evaluated once per RRTConnect iteration
        return checker.checks - checks0 >= budget or time.perf_counter() > wall_end

    with _ompl_log_level(ou.LOG_WARN):
        status = setup.solve(ob.PlannerTerminationCondition(used_up))
    t_plan = time.perf_counter() - t0
    if not setup.haveExactSolutionPath():
        free = [c for c in (checker.contacts(q_start), checker.contacts(q_goal)) if c]
        why = f" ({checker.describe(free[0])})" if free else ""
        raise GroundingError(
            f"no collision-free arm path found in {budget} collision checks (~{timeout:.2f} s; "
            f"OMPL: {status}){why}"
        )
    path = setup.getSolutionPath()
    t1 = time.perf_counter()
    _simplify(setup.getPathSimplifier(), path, simplify_time)
    t_simp = time.perf_counter() - t1
    states = path.getStates()
    vertices = np.array([[s[i] for i in range(7)] for s in states])
    return vertices, t_plan, t_simp


def _simplify(simplifier: og.PathSimplifier, path: og.PathGeometric, budget: float) -> None:
    """Shortcut rounds (at most 20) until a round changes nothing or `budget` seconds pass.

    The budget is only checked between rounds, so results stay reproducible unless it is
    exhausted; the default (5 s) is a safety net far above what the rounds take (measured:
    ~20 ms mean, <50 ms max per plan on 2 idle cores), so that equal seeds give equal paths
    on a loaded machine too (a 0.15 s budget could run out there).
    """
    t_end = time.perf_counter() + budget
    for _ in range(20):
        changed = simplifier.reduceVertices(path)
        changed |= simplifier.partialShortcutPath(path)
        changed |= simplifier.collapseCloseVertices(path)
        if not changed or time.perf_counter() > t_end:
            break


@contextmanager
def _ompl_log_level(level: ou.LogLevel) -> Iterator[None]:
    previous = ou.getLogLevel()
    ou.setLogLevel(level)
    try:
        yield
    finally:
        ou.setLogLevel(previous)


# ---------------------------------------------------------------------- timing
def time_parameterize(
    path: np.ndarray,
    vel_limits: np.ndarray,
    acc_limits: np.ndarray,
    dt: float,
    *,
    lead: float = 0.0,
    corner_cos: float = 0.9999,
) -> np.ndarray:
    """Joint setpoints every `dt` s following `path` exactly with trapezoidal speed.

    The path is cut at corners (consecutive directions with cosine < `corner_cos`)
    where the arm stops; each straight piece gets its own trapezoidal profile within
    the per-joint limits. Row k is the setpoint for time (k+1)*dt; the last row is
    the goal. `lead` (s) adds velocity feed-forward (setpoint + lead * velocity),
    which cancels the lag of a position servo with kv/kp = lead.
    """
    path = _dedupe(np.asarray(path, dtype=float))
    vel = np.asarray(vel_limits, dtype=float)
    acc = np.asarray(acc_limits, dtype=float)
    if np.any(vel <= 0) or np.any(acc <= 0) or dt <= 0:
        raise GroundingError("velocity/acceleration limits and dt must be positive")
    if len(path) < 2:
        return path[-1:].copy()
    seg = np.diff(path, axis=0)
    length = np.linalg.norm(seg, axis=1)
    unit = seg / length[:, None]
    cuts = [0]
    cuts += [i + 1 for i in range(len(unit) - 1) if unit[i] @ unit[i + 1] < corner_cos]
    cuts.append(len(seg))
    out = []
    for a, b in itertools.pairwise(cuts):
        out.append(_trapezoid_piece(path[a : b + 1], unit[a:b], length[a:b], vel, acc, dt, lead))
    return np.concatenate(out)


def _dedupe(path: np.ndarray) -> np.ndarray:
    keep = np.ones(len(path), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(path, axis=0), axis=1) > 1e-9
    return path[keep]


def _trapezoid_piece(
    points: np.ndarray,
    unit: np.ndarray,
    length: np.ndarray,
    vel: np.ndarray,
    acc: np.ndarray,
    dt: float,
    lead: float,
) -> np.ndarray:
    absu = np.maximum(np.abs(unit), 1e-12)
    v_max = float(np.min(vel / absu))  # path speed (rad/s along the path) per joint limits
    a_max = float(np.min(acc / absu))
    total = float(length.sum())
    if total < v_max**2 / a_max:  # triangular profile
        v_peak = np.sqrt(total * a_max)
        t_acc, t_flat = v_peak / a_max, 0.0
    else:
        v_peak = v_max
        t_acc, t_flat = v_max / a_max, (total - v_max**2 / a_max) / v_max
    duration = 2 * t_acc + t_flat
    steps = max(1, int(np.ceil(duration / dt - 1e-9)))
    stretch = duration / (steps * dt)  # slow down slightly so the piece ends on a tick
    t = np.arange(1, steps + 1) * dt * stretch
    a, vp = a_max, v_peak
    t_dec = t_acc + t_flat
    s = np.where(
        t < t_acc,
        0.5 * a * t**2,
        np.where(
            t < t_dec, 0.5 * a * t_acc**2 + vp * (t - t_acc), total - 0.5 * a * (duration - t) ** 2
        ),
    )
    sdot = np.where(t < t_acc, a * t, np.where(t < t_dec, vp, a * (duration - t))) * stretch
    s = np.clip(s, 0.0, total)
    s[-1] = total
    cum = np.concatenate([[0.0], np.cumsum(length)])
    q = np.column_stack([np.interp(s, cum, points[:, j]) for j in range(points.shape[1])])
    if lead:
        idx = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(unit) - 1)
        q = q + lead * sdot[:, None] * unit[idx]
    return q
