"""The evaluation sweep: every scene × method × seed of a suite, in parallel, resumable.

Runs go to spawn-started worker processes (`ProcessPoolExecutor`), at most one per
worker in flight, so when a worker process dies (`BrokenProcessPool`) the suspects
are known: each is re-run alone in a fresh pool, the one that kills it again is
recorded as a failure row, and the sweep continues with a fresh pool. Every finished
row is appended to ``results.csv`` at once (flush + fsync), and re-running with the
same output directory skips the rows already there.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from utamp_gym.backend import DEFAULT_POSE_NOISE, MAX_POSE_NOISE
from utamp_gym.errors import UnknownNameError, UtampError
from utamp_gym.eval.records import GROUNDINGS, ResultRow, ResultsFile
from utamp_gym.eval.runner import DEFAULT_TIMEOUT, EvalTask, check_method, failure_row, run_task
from utamp_gym.eval.vlm_methods import VLM_METHODS
from utamp_gym.planning.methods import DEFAULT_NOISE
from utamp_gym.suites import suite_scenes

DEFAULT_METHODS = ("utamp1", "utamp2-gt", "utamp2-rules", "utamp2-noisy")
NO_SLIDING = ("utamp1",)  # U-TAMP-1 has no slide-support action (skipped, as in the paper)
WORKER_DIED = "crashed: the worker process died (killed or crashed hard) while running this"
Runner = Callable[[EvalTask], ResultRow]
Record = Callable[[ResultRow], None]


@dataclass(frozen=True)
class SweepConfig:
    """What to evaluate. Several `noise` levels make a noise sweep of ``utamp2-noisy``."""

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

    def __post_init__(self) -> None:
        for m in self.methods:
            check_method(m, self.suite)  # planners, VLM methods and rl:PATH models
        if self.grounding not in GROUNDINGS:
            raise UnknownNameError("grounding", self.grounding, GROUNDINGS)
        if self.seeds < 1 or (self.limit is not None and self.limit < 1):
            raise UtampError("--seeds and --limit must be at least 1")
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


def plan_tasks(cfg: SweepConfig) -> tuple[list[EvalTask], list[str]]:
    """The tasks of a sweep, most expensive first, and notes on what was skipped."""
    scenes = suite_scenes(cfg.suite)[: cfg.limit]
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
                for seed in range(cfg.seeds):
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
                    )
                    cost = scene.n_objects * (20 if method == "utamp1" else 1)
                    cost *= 50 if method in VLM_METHODS else 1
                    tasks.append((cost, task))
    tasks.sort(key=lambda ct: -ct[0])  # longest first: better load balance
    return [t for _, t in tasks], notes


def _pool_pass(
    tasks: deque[EvalTask], workers: int, runner: Runner, record: Record
) -> list[EvalTask]:
    """Run `tasks` in one pool until done or the pool breaks; returns the suspects."""
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    inflight: dict[Future[ResultRow], EvalTask] = {}
    interrupted = True
    try:
        while tasks or inflight:
            while tasks and len(inflight) < workers:
                task = tasks.popleft()
                try:
                    inflight[pool.submit(runner, task)] = task
                except BrokenProcessPool:
                    tasks.appendleft(task)
                    interrupted = False
                    return list(inflight.values())
            done, _ = wait(inflight, return_when=FIRST_COMPLETED)
            broken = []
            for fut in done:
                task = inflight.pop(fut)
                try:
                    record(fut.result())
                except BrokenProcessPool:
                    broken.append(task)
                except Exception as exc:  # e.g. the result could not be pickled
                    record(failure_row(task, f"crashed: {type(exc).__name__}: {exc}"))
            if broken:
                interrupted = False
                return [*broken, *inflight.values()]
        interrupted = False
        return []
    finally:  # on Ctrl-C do not wait for running tasks
        pool.shutdown(wait=not interrupted, cancel_futures=True)


def execute(tasks: Sequence[EvalTask], workers: int, runner: Runner, record: Record) -> None:
    """Run every task (in-process when `workers` is 0) and record each row once."""
    if workers <= 0:
        for task in tasks:
            try:
                row = runner(task)
            except Exception as exc:  # a custom runner; `run_task` itself never raises
                row = failure_row(task, f"crashed: {type(exc).__name__}: {exc}")
            record(row)
        return
    pending = deque(tasks)
    while pending:
        suspects = _pool_pass(pending, workers, runner, record)
        if len(suspects) == 1:
            record(failure_row(suspects[0], WORKER_DIED))
            continue
        for task in suspects:  # find the culprit: each suspect alone
            if _pool_pass(deque([task]), 1, runner, record):
                record(failure_row(task, WORKER_DIED))


def run_sweep(
    cfg: SweepConfig,
    out: str | Path,
    *,
    workers: int | None = None,
    progress: bool = True,
    runner: Runner = run_task,
) -> SweepReport:
    """Run the sweep into `out` (results.csv, resumable); summaries are written by the caller."""
    if any(m in VLM_METHODS for m in cfg.methods):
        from utamp_gym.eval.vlm_client import VlmConfig

        VlmConfig.from_env()  # fail fast without an endpoint
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tasks, notes = plan_tasks(cfg)
    results = ResultsFile(out / "results.csv")
    todo = [t for t in tasks if t.key not in results]
    workers = (os.cpu_count() or 1) if workers is None else workers
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

        execute(todo, min(workers, len(todo)) if workers > 0 else 0, runner, record)
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
    from utamp_gym.eval.plots import write_plots
    from utamp_gym.eval.summary import summarize, write_summary

    cfg = report.config
    context = {
        "suite": cfg.suite,
        "grounding": cfg.grounding,
        "closed_loop": cfg.closed_loop,
        "disturbance": cfg.disturbance,
        "pose_noise_m": cfg.pose_noise if cfg.grounding == "physics" else None,
        "methods_requested": list(cfg.methods),
        "seeds": cfg.seeds,
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
