"""Plan a scene symbolically, then execute the plan step by step in physics.

`run_episode` is the end-to-end check of one scene: `plan_scene` gives the macro
actions, `MujocoBackend` executes them and stops at the first failure, and the
result reports what physics measured (the tower standing on the tray, the final
object poses), with planning, execution and per-step timings. Optionally it writes
a headless video of the execution (MP4 via imageio-ffmpeg, or GIF).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.model import Scene
from utamp_gym.sim.backend import FrameSink, MujocoBackend

VIDEO_SIZE = (480, 360)  # width, height
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
    final_stack: list[str]  # standing on the tray, bottom -> top, measured
    object_poses: dict[str, list[float]]  # name -> [x, y, z, qw, qx, qy, qz]
    planning_time_s: float
    execution_time_s: float
    wall_time_s: float
    steps: list[StepRecord] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def run_episode(
    scene: Scene | str,
    method: str = "utamp2-gt",
    seed: int = 0,
    video: str | Path | None = None,
    *,
    backend: MujocoBackend | None = None,
) -> EpisodeResult:
    """Plan `scene` with `method`, execute it in MuJoCo and measure the result.

    `seed` drives the planner's randomness and, through one generator, the pose noise,
    IK restarts and OMPL: the same seed gives the same rollout. Execution stops at the
    first failed step. `success` means every step succeeded and all objects stand in
    one tower on the tray, as simulated.
    """
    if isinstance(scene, str):
        from utamp_gym.suites import resolve_scene

        scene = resolve_scene(scene)
    t0 = time.perf_counter()
    outcome = plan_scene(scene, method, seed=seed)
    plan = list(outcome.plan)
    with _video(video) as sink:
        own = backend is None
        sim = backend or MujocoBackend()
        sim.frame_sink = sink
        try:
            t_exec = time.perf_counter()
            sim.reset(scene, np.random.default_rng(seed))
            if sink is not None:
                sink(sim.render(*VIDEO_SIZE))
            steps, failure = _execute(sim, plan) if outcome.solved else ([], None)
            if sink is not None:
                sink(sim.render(*VIDEO_SIZE))
            execution_time = time.perf_counter() - t_exec
            final_stack = sim.stacked_on_tray()
            poses = {n: [float(v) for v in p] for n, p in sim.object_poses().items()}
        finally:
            sim.frame_sink = None
            if own:
                sim.close()
    others = set(scene.object_names) - {scene.tower_base}
    if not outcome.solved:
        failure = {"step": None, "action": None, "reason": f"not planned: {outcome.reason}"}
    elif failure is None and set(final_stack) != others:
        failure = {
            "step": len(plan),
            "action": None,
            "reason": f"goal not reached: the tray holds {final_stack or 'nothing'}",
        }
    return EpisodeResult(
        scene=scene.name,
        method=method,
        seed=seed,
        solved=outcome.solved,
        plan=plan,
        success=outcome.solved and failure is None,
        failure=failure,
        final_stack=final_stack,
        object_poses=poses,
        planning_time_s=outcome.planning_time_s,
        execution_time_s=execution_time,
        wall_time_s=time.perf_counter() - t0,
        steps=steps,
    )


def _execute(sim: MujocoBackend, plan: list[str]) -> tuple[list[StepRecord], dict[str, Any] | None]:
    steps: list[StepRecord] = []
    for i, action in enumerate(plan):
        res = sim.execute(action)
        steps.append(StepRecord(i, action, res.success, res.reason, dict(res.timings)))
        if not res.success:
            return steps, {"step": i, "action": action, "reason": res.reason}
    return steps, None


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
