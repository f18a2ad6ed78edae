"""Plan a scene symbolically, then execute the plan step by step in physics.

`run_episode` is the end-to-end check of one scene: `plan_scene` gives the macro
actions and `execute_plan` has `MujocoBackend` execute them, stopping at the first
failure (`execute_plan` alone replays any given plan, e.g. a VLM's). The result
reports what physics measured (the tower standing on the tray, the final object
poses), with planning, execution and per-step timings. Optionally it writes
a headless video of the execution (MP4 via imageio-ffmpeg, or GIF).
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.backend import DEFAULT_PERCEPTION, DEFAULT_POSE_NOISE
from utamp_gym.grounding import physics_backend
from utamp_gym.planning.methods import PlanOutcome, plan_scene
from utamp_gym.scene.model import Scene
from utamp_gym.seeding import run_seed
from utamp_gym.sim.backend import FrameSink, MujocoBackend

VIDEO_SIZE = (480, 360)  # width, height
FAULT_STREAM = 0xFA17  # second generator of a seed: injected faults (open loop)
VIDEO_PERIOD = 0.1  # s of simulated time per frame


@dataclass(frozen=True)
class StepRecord:
    """One executed macro action and its timings (s; see `control.Timings`)."""

    step: int
    action: str
    success: bool
    reason: str | None
    timings: dict[str, float]


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of `run_episode`; `to_dict()` gives plain JSON-able data."""

    scene: str
    method: str
    seed: int
    solved: bool
    plan: list[str]
    success: bool
    failure: dict[str, Any] | None  # {step, action, reason}
    final_stack: list[str]  # standing on the tower base (`Scene.tower_base`), bottom -> top
    object_poses: dict[str, list[float]]  # name -> [x, y, z, qw, qx, qy, qz]
    planning_time_s: float
    execution_time_s: float
    wall_time_s: float
    n_faults: int = 0
    steps: list[StepRecord] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Execution:
    """What physics measured while executing one plan (see `execute_plan`)."""

    success: bool
    failure: dict[str, Any] | None  # {step, action, reason}
    final_stack: list[str]
    object_poses: dict[str, list[float]]
    execution_time_s: float
    steps: list[StepRecord]
    n_faults: int = 0

    @property
    def failure_reason(self) -> str:
        """One line: ``""`` on success, else ``step I ACTION: REASON`` or the goal shortfall."""
        f = self.failure
        if f is None:
            return ""
        if f["action"] is None:
            return f["reason"]
        return f"step {f['step']} {f['action']}: {f['reason']}"


def execute_plan(
    scene: Scene,
    plan: Sequence[str],
    seed: int = 0,
    video: str | Path | None = None,
    *,
    backend: MujocoBackend | None = None,
    pose_noise: float = DEFAULT_POSE_NOISE,
    disturbance: float = 0.0,
    perception: str = DEFAULT_PERCEPTION,
) -> Execution:
    """Execute `plan` on `scene` in MuJoCo, stopping at the first failed step (open loop).

    `seed`, mixed with the scene's name (`utamp_gym.seeding.run_seed`), feeds one generator
    for initial pose noise, pose estimates, IK restarts and OMPL; `pose_noise` is the
    robot's pose-estimation noise (m; ignored when `backend` is given: its own applies),
    `perception` where its pose estimates come from (``gaussian`` or ``rgbd``: the cameras).
    With `disturbance` p, each executed step is followed with probability p by an injected
    fault (drawn from a second generator of that seed).
    `success` means every step succeeded and all objects stand in one tower on the tray,
    as simulated.
    """
    plan = list(plan)
    base = run_seed(scene.name, seed)  # independent per (scene, seed)
    faults = np.random.default_rng([base, FAULT_STREAM]) if disturbance > 0 else None
    with _video(video) as sink:
        own = backend is None
        sim = backend or physics_backend(pose_noise=pose_noise, perception=perception)
        sim.frame_sink = sink
        try:
            start = time.perf_counter()
            sim.reset(scene, np.random.default_rng(base))
            if sink is not None:
                sink(sim.render(*VIDEO_SIZE))
            steps, failure, n_faults = _execute(sim, plan, disturbance, faults)
            if sink is not None:
                sink(sim.render(*VIDEO_SIZE))
            elapsed = time.perf_counter() - start
            final_stack = sim.stacked_on_tray()
            poses = {n: [float(v) for v in p] for n, p in sim.object_poses().items()}
        finally:
            sim.frame_sink = None
            if own:
                sim.close()
    others = set(scene.object_names) - {scene.tower_base}
    if failure is None and set(final_stack) != others:
        failure = {
            "step": len(plan),
            "action": None,
            "reason": f"goal not reached: {scene.tower_base} holds {final_stack or 'nothing'}",
        }
    return Execution(failure is None, failure, final_stack, poses, elapsed, steps, n_faults)


def run_episode(
    scene: Scene | str,
    method: str = "utamp2-gt",
    seed: int = 0,
    video: str | Path | None = None,
    *,
    backend: MujocoBackend | None = None,
    pose_noise: float = DEFAULT_POSE_NOISE,
    disturbance: float = 0.0,
    perception: str = DEFAULT_PERCEPTION,
) -> EpisodeResult:
    """Plan `scene` with `method`, execute it in MuJoCo (`execute_plan`) and measure.

    `seed` drives the planner's randomness and the physics generator: the same seed
    gives the same rollout. An unsolved scene is not executed (its poses are measured
    after reset). `pose_noise`, `disturbance` and `perception` as in `execute_plan`.
    Method ``utamp2-perceived`` looks at the scene first: use
    `utamp_gym.eval.perceived.run_perceived_episode`.
    """
    if isinstance(scene, str):
        from utamp_gym.suites import resolve_scene

        scene = resolve_scene(scene)
    t0 = time.perf_counter()
    outcome = plan_scene(scene, method, seed=seed)
    return episode_result(
        scene, outcome, outcome.plan, seed, video, t0, backend, pose_noise, disturbance, perception
    )


def episode_result(
    scene: Scene,
    outcome: PlanOutcome,
    plan: Sequence[str],
    seed: int,
    video: str | Path | None,
    t0: float,
    backend: MujocoBackend | None,
    pose_noise: float,
    disturbance: float,
    perception: str,
) -> EpisodeResult:
    """Execute `plan` (the world's names of `outcome`'s plan) and report the episode."""
    ex = execute_plan(
        scene,
        plan if outcome.solved else (),
        seed,
        video,
        backend=backend,
        pose_noise=pose_noise,
        disturbance=disturbance,
        perception=perception,
    )
    failure = ex.failure
    if not outcome.solved:
        failure = {"step": None, "action": None, "reason": f"not planned: {outcome.reason}"}
    return EpisodeResult(
        scene=scene.name,
        method=outcome.method,
        seed=seed,
        solved=outcome.solved,
        plan=list(plan),
        success=outcome.solved and failure is None,
        failure=failure,
        final_stack=ex.final_stack,
        object_poses=ex.object_poses,
        planning_time_s=outcome.planning_time_s,
        execution_time_s=ex.execution_time_s,
        wall_time_s=time.perf_counter() - t0,
        n_faults=ex.n_faults,
        steps=ex.steps,
    )


def _execute(
    sim: MujocoBackend, plan: list[str], disturbance: float, faults: np.random.Generator | None
) -> tuple[list[StepRecord], dict[str, Any] | None, int]:
    steps: list[StepRecord] = []
    n_faults = 0
    for i, action in enumerate(plan):
        res = sim.execute(action)
        steps.append(StepRecord(i, action, res.success, res.reason, dict(res.timings)))
        if not res.success:
            return steps, {"step": i, "action": action, "reason": res.reason}, n_faults
        if faults is not None and faults.random() < disturbance:
            n_faults += sim.disturb(faults) is not None
    return steps, None, n_faults


@contextmanager
def _video(path: str | Path | None) -> Iterator[FrameSink | None]:
    """A frame sink writing `path` (.mp4 through imageio-ffmpeg, .gif otherwise)."""
    if path is None:
        yield None
        return
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fps = round(1 / VIDEO_PERIOD)
    if path.suffix.lower() == ".gif":
        writer = imageio.get_writer(path, mode="I", duration=1000 * VIDEO_PERIOD, loop=0)
    else:
        writer = imageio.get_writer(path, fps=fps, codec="libx264", macro_block_size=8)
    try:
        yield writer.append_data
    finally:
        writer.close()
