"""The evaluation sweep: every scene × method × seed of a suite, in parallel, resumable.

The runs go to an executor (`utamp_gym.distributed`: worker processes on this machine,
or Ray tasks on a cluster), which records each finished row once, even for a run that
crashed or killed its worker. Every finished row is appended to ``results.csv`` at once
(flush + fsync), and re-running with the same output directory, with either executor,
skips the rows already there, except crashed ones (an exception or a dead worker), which run
again. `SweepReport.crashed` lists the crashed rows of the sweep; ``utamp eval`` names them on
stderr and exits 1. `--seed-offset`, `--scenes` and `--shard` select a part
of a sweep so that several machines can share one (`utamp eval merge` joins them).
"""

from __future__ import annotations

import fnmatch
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from utamp_gym.affordances.sources import DEFAULT_NOISE
from utamp_gym.backend import (
    DEFAULT_PERCEPTION,
    DEFAULT_POSE_NOISE,
    MAX_POSE_NOISE,
    PERCEPTION_MODES,
)
from utamp_gym.distributed import Executor, LocalExecutor
from utamp_gym.errors import UnknownNameError, UtampError
from utamp_gym.eval.records import GROUNDINGS, ResultRow, ResultsFile, key_shard
from utamp_gym.eval.runner import DEFAULT_TIMEOUT, EvalTask, check_method, failure_row, run_task
from utamp_gym.eval.summary import summarize, write_summary
from utamp_gym.methods.vlm import VLM_METHODS
from utamp_gym.methods.vlm_client import VlmConfig
from utamp_gym.provenance import commit
from utamp_gym.scene.model import Scene
from utamp_gym.suites import suite_scenes

DEFAULT_METHODS = ("utamp1", "utamp2-gt", "utamp2-rules", "utamp2-noisy")
NO_SLIDING = ("utamp1",)  # U-TAMP-1 has no slide-support action (skipped, as in the paper)
Runner = Callable[[EvalTask], ResultRow]


@dataclass(frozen=True)
class SweepConfig:
    """What to evaluate. Several `noise` levels make a noise sweep of ``utamp2-noisy``.

    Seeds are ``seed_offset .. seed_offset + seeds - 1``; `scenes` is a glob over scene
    names (``pick-place/0*``), applied before `limit`; ``shard=(i, n)`` keeps the runs whose
    key hashes to the i-th of n parts (1 <= i <= n), so n machines split one sweep.
    """

    suite: str
    methods: tuple[str, ...] = DEFAULT_METHODS
    seeds: int = 1
    grounding: str = "physics"
    limit: int | None = None
    noise: tuple[float, ...] = (DEFAULT_NOISE,)
    timeout: float = DEFAULT_TIMEOUT
    explain: bool = True
    closed_loop: bool = False
    disturbance: float = 0.0
    pose_noise: float = DEFAULT_POSE_NOISE  # physics only (symbolic rows record None)
    perception: str = DEFAULT_PERCEPTION  # physics only: where the robot's poses come from
    seed_offset: int = 0
    scenes: str | None = None
    shard: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        for m in self.methods:
            check_method(m, self.suite)  # planners, VLM methods and rl:PATH models
        if self.grounding not in GROUNDINGS:
            raise UnknownNameError("grounding", self.grounding, GROUNDINGS)
        if self.seeds < 1 or (self.limit is not None and self.limit < 1):
            raise UtampError("--seeds and --limit must be at least 1")
        if self.seed_offset < 0:
            raise UtampError(f"--seed-offset must be at least 0, got {self.seed_offset}")
        if self.shard is not None and not 1 <= self.shard[0] <= self.shard[1]:
            i, n = self.shard
            raise UtampError(f"--shard I/N needs 1 <= I <= N, got {i}/{n}")
        if not self.noise or any(not 0.0 <= p <= 1.0 for p in self.noise):
            raise UtampError(f"noise levels must be in [0, 1], got {list(self.noise)}")
        if not 0.0 <= self.disturbance <= 1.0:
            raise UtampError(f"--disturbance must be in [0, 1], got {self.disturbance}")
        if self.disturbance > 0 and self.grounding != "physics":
            raise UtampError("--disturbance needs --grounding physics (faults are physical)")
        if self.closed_loop and any(m in VLM_METHODS for m in self.methods):
            raise UtampError(
                "--closed-loop runs the planner policy; it does not support "
                + ", ".join(m for m in self.methods if m in VLM_METHODS)
            )
        if self.perception not in PERCEPTION_MODES:
            raise UnknownNameError("perception", self.perception, PERCEPTION_MODES)
        if self.perception != DEFAULT_PERCEPTION and self.grounding != "physics":
            raise UtampError("--perception rgbd needs --grounding physics (poses are physical)")
        if not 0.0 <= self.pose_noise <= MAX_POSE_NOISE:
            raise UtampError(
                f"--pose-noise must be in [0, {MAX_POSE_NOISE}] m, got {self.pose_noise}"
            )


@dataclass
class SweepReport:
    """The rows of this sweep's configuration and what the run did."""

    config: SweepConfig
    out: Path
    rows: list[ResultRow]
    ran: int
    resumed: int
    notes: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0

    @property
    def crashed(self) -> list[ResultRow]:
        """The rows of runs that crashed (raised, or their worker died): not outcomes."""
        return [r for r in self.rows if r.crashed]


def parse_shard(text: str) -> tuple[int, int]:
    """``"I/N"`` -> ``(I, N)`` (1 <= I <= N): the I-th of N parts of a sweep."""
    try:
        i, n = (int(part) for part in text.split("/"))
    except ValueError:
        raise UtampError(f"--shard: expected I/N such as 2/3, got {text!r}") from None
    if not 1 <= i <= n:
        raise UtampError(f"--shard I/N needs 1 <= I <= N, got {text!r}")
    return i, n


def select_scenes(cfg: SweepConfig) -> tuple[Scene, ...]:
    """The suite's scenes matching `cfg.scenes` (a glob), then the first `cfg.limit`."""
    scenes = suite_scenes(cfg.suite)
    if cfg.scenes is not None:
        matched = tuple(s for s in scenes if fnmatch.fnmatchcase(s.name, cfg.scenes))
        if not matched:
            shown = ", ".join(s.name for s in scenes[:3])
            raise UtampError(
                f"--scenes {cfg.scenes!r} matches no scene of the {cfg.suite} suite "
                f"({len(scenes)} scenes named like {shown}, ...; e.g. {cfg.suite}/0*)"
            )
        scenes = matched
    return scenes[: cfg.limit]


def plan_tasks(cfg: SweepConfig) -> tuple[list[EvalTask], list[str]]:
    """The tasks of a sweep (or of its shard), most expensive first, and notes on skips."""
    scenes = select_scenes(cfg)
    seeds = range(cfg.seed_offset, cfg.seed_offset + cfg.seeds)
    notes = []
    methods = list(cfg.methods)
    if cfg.suite == "sliding":
        for m in NO_SLIDING:
            if m in methods:
                methods.remove(m)
                notes.append(f"{m} skipped on the sliding suite: its domain has no slide action")
    tasks: list[tuple[float, EvalTask]] = []
    for scene in scenes:
        for method in methods:
            levels: Sequence[float | None] = cfg.noise if method == "utamp2-noisy" else (None,)
            for noise in levels:
                for seed in seeds:
                    task = EvalTask(
                        scene.name,
                        method,
                        seed,
                        cfg.grounding,
                        noise,
                        cfg.timeout,
                        cfg.explain,
                        closed_loop=cfg.closed_loop,
                        disturbance=cfg.disturbance,
                        pose_noise=cfg.pose_noise if cfg.grounding == "physics" else None,
                        perception=cfg.perception,
                    )
                    if cfg.shard and key_shard(task.key, cfg.shard[1]) != cfg.shard[0] - 1:
                        continue
                    cost = scene.n_objects * (20 if method == "utamp1" else 1)
                    cost *= 3 if method.startswith("utamp2-perceived") else 1
                    cost *= 50 if method in VLM_METHODS else 1
                    tasks.append((cost, task))
    tasks.sort(key=lambda ct: -ct[0])  # longest first: better load balance
    return [t for _, t in tasks], notes


def run_sweep(
    cfg: SweepConfig,
    out: str | Path,
    *,
    workers: int | None = None,
    progress: bool = True,
    runner: Runner = run_task,
    executor: Executor | None = None,
) -> SweepReport:
    """Run the sweep into `out` (results.csv, resumable); summaries are written by the caller.

    `executor` defaults to worker processes on this machine (`workers` of them: None for
    the CPU count, 0 to run in this process); `runner` must be picklable for both.
    """
    if any(m in VLM_METHODS for m in cfg.methods):
        VlmConfig.from_env()  # fail fast without an endpoint
    start = time.perf_counter()
    commit()  # the provenance of this run's results: the code as it is now
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tasks, notes = plan_tasks(cfg)
    results = ResultsFile(out / "results.csv")
    # crashed rows are run again (the cause may be fixed); finished ones are kept
    todo = [t for t in tasks if t.key not in results or results.rows[t.key].crashed]
    executor = LocalExecutor(workers) if executor is None else executor
    from tqdm import tqdm

    with tqdm(
        total=len(todo),
        desc=f"eval {cfg.suite} ({cfg.grounding})",
        unit="run",
        disable=not progress,
        dynamic_ncols=True,
    ) as bar:
        ok = 0

        def record(row: ResultRow) -> None:
            nonlocal ok
            results.append(row)
            ok += row.success
            bar.update(1)
            bar.set_postfix(success=f"{ok}/{bar.n}")

        executor.run(runner, todo, record, failure_row)
    results.sort()
    rows = [results.rows[t.key] for t in tasks if t.key in results]
    return SweepReport(
        cfg,
        out,
        rows,
        ran=len(todo),
        resumed=len(tasks) - len(todo),
        notes=notes,
        wall_time_s=time.perf_counter() - start,
    )


def write_outputs(report: SweepReport) -> dict[str, Any]:
    """Write summary.md, summary.json and the figures of a sweep; returns the summary."""
    # lazy: utamp_gym.eval.plots imports matplotlib
    from utamp_gym.eval.plots import write_plots  # matplotlib: only when figures are written

    cfg = report.config
    context = {
        "suite": cfg.suite,
        "grounding": cfg.grounding,
        "closed_loop": cfg.closed_loop,
        "disturbance": cfg.disturbance,
        "pose_noise_m": cfg.pose_noise if cfg.grounding == "physics" else None,
        "perception": cfg.perception,
        "methods_requested": list(cfg.methods),
        "seeds": cfg.seeds,
        "seed_offset": cfg.seed_offset,
        "scene_pattern": cfg.scenes,
        "shard": None if cfg.shard is None else f"{cfg.shard[0]}/{cfg.shard[1]}",
        "scenes": len({r.scene for r in report.rows}),
        "noise_levels": list(cfg.noise),
        "planner_timeout_s": cfg.timeout,
        "notes": report.notes,
        "wall_time_s": round(report.wall_time_s, 3),
        "resumed_rows": report.resumed,
    }
    summary = summarize(report.rows, context=context)
    write_summary(report.out, summary)
    write_plots(report.out, summary)
    return summary
