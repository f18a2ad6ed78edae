"""`--executor ray` on a local Ray instance (2 CPUs): same rows as the local executor, dead
workers retried or recorded, an interrupted sweep resumable, no Ray process left behind."""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Iterator
from functools import partial
from pathlib import Path

import pytest

from utamp_gym.cli import main
from utamp_gym.distributed import WORKER_DIED, LocalExecutor, RayExecutor
from utamp_gym.eval.records import ResultRow, ResultsFile, read_rows
from utamp_gym.eval.runner import EvalTask, run_task
from utamp_gym.eval.sweep import SweepConfig, run_sweep

ray = pytest.importorskip("ray")
# the runners below are sent to Ray workers by value: they cannot import this test module
ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])

SYMBOLIC = SweepConfig("pick-place", ("utamp2-gt",), grounding="symbolic", limit=4)


def _ray_processes() -> set[int]:
    """Descendants of this process that belong to Ray (GCS, raylet, agents, workers)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            children.setdefault(ppid, []).append(int(entry))
    found, todo = set(), [os.getpid()]
    while todo:
        for pid in children.get(todo.pop(), []):
            todo.append(pid)
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if b"ray" in cmd:
                found.add(pid)
    return found


def _wait_gone(pids: set[int], timeout: float = 20.0) -> set[int]:
    """The `pids` still alive (not zombies) after up to `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while True:
        alive = set()
        for pid in pids:
            try:
                state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
            except OSError:
                continue
            if state != "Z":
                alive.add(pid)
        if not alive or time.monotonic() > deadline:
            return alive
        time.sleep(0.2)


def _shutdown_and_check() -> None:
    pids = _ray_processes()
    ray.shutdown()
    assert not _wait_gone(pids), "Ray processes left behind after shutdown"


@pytest.fixture(scope="module")
def _ray_module() -> Iterator[None]:
    """Shuts down whatever Ray instance this module's tests left running."""
    yield
    if ray.is_initialized():
        _shutdown_and_check()


@pytest.fixture
def ray_instance(_ray_module: None) -> object:
    """A local Ray instance with 2 CPUs, shared by the tests that use it."""
    if not ray.is_initialized():
        ray.init(
            address="local",
            num_cpus=2,
            include_dashboard=False,
            log_to_driver=False,
            logging_level="warning",
        )
    return ray


def _outcomes(rows: list[ResultRow]) -> dict[object, dict[str, str]]:
    return {r.key: r.outcome() for r in rows}


@pytest.mark.physics
def test_cli_ray_physics_sweep_equals_local(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, _ray_module: None
) -> None:
    """`utamp eval --executor ray --workers 2` starts a 2-CPU Ray instance, runs a physics
    sweep there, gives the local executor's rows (wall-clock columns excepted), and leaves
    no Ray process behind."""
    if ray.is_initialized():  # this test is about the executor's own instance
        ray.shutdown()
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    methods = ("utamp2-gt", "utamp2-noisy")  # noisy detection is seeded: seeds must agree
    cfg = SweepConfig("pick-place", methods, seeds=2, scenes="pick-place/000", noise=(0.05,))
    local = run_sweep(cfg, tmp_path / "local", executor=LocalExecutor(2), progress=False)
    assert len(local.rows) == 4

    seen: dict[str, set[int]] = {}
    append = ResultsFile.append

    def spy(self: ResultsFile, row: ResultRow) -> None:  # snapshot Ray's processes mid-sweep
        seen.setdefault("pids", _ray_processes())
        append(self, row)

    monkeypatch.setattr(ResultsFile, "append", spy)
    args = ["eval", "--suite", "pick-place", "--methods", ",".join(methods), "--noise", "0.05"]
    args += ["--seeds", "2", "--scenes", "pick-place/000"]
    args += ["--executor", "ray", "--workers", "2"]
    assert main([*args, "--quiet", "--out", str(tmp_path / "ray")]) == 0
    assert not ray.is_initialized()
    assert seen["pids"], "no Ray process ran the sweep"
    assert not _wait_gone(seen["pids"]), "Ray processes left behind"
    ray_rows = read_rows(tmp_path / "ray" / "results.csv")
    assert _outcomes(ray_rows) == _outcomes(local.rows)
    f1 = {r.seed: r.affordance_f1 for r in ray_rows if r.method == "utamp2-noisy"}
    assert f1[0] != f1[1]  # the seeds' detections differ, and each executor reproduced them
    gt = [r for r in ray_rows if r.method == "utamp2-gt"]
    assert all(r.success and r.execution_time_s > 0 for r in gt)  # physics built the towers


def _die_once(marker_dir: str, task: EvalTask) -> ResultRow:
    """Kills its own worker (SIGKILL) on the first attempt at scene 001; 002 raises."""
    marker = Path(marker_dir) / task.scene.replace("/", "_")
    attempts = len(marker.read_text()) if marker.exists() else 0
    marker.write_text("x" * (attempts + 1))
    if task.scene == "pick-place/001" and attempts == 0:
        os.kill(os.getpid(), signal.SIGKILL)
    if task.scene == "pick-place/002":
        raise RuntimeError("boom")
    return run_task(task)


def _always_dies(task: EvalTask) -> ResultRow:
    if task.scene == "pick-place/001":
        os.kill(os.getpid(), signal.SIGKILL)
    return run_task(task)


def test_killed_worker_is_retried_by_ray(tmp_path: Path, ray_instance: object) -> None:
    runner = partial(_die_once, str(tmp_path))
    report = run_sweep(
        SYMBOLIC, tmp_path / "out", runner=runner, executor=RayExecutor(max_retries=2)
    )
    rows = {r.scene: r for r in report.rows}
    assert len(rows) == 4 and len(read_rows(tmp_path / "out" / "results.csv")) == 4
    assert (tmp_path / "pick-place_001").read_text() == "xx"  # killed once, then retried
    assert rows["pick-place/001"].success and not rows["pick-place/001"].crashed
    assert (tmp_path / "pick-place_002").read_text() == "x"  # an exception is not retried
    assert rows["pick-place/002"].crashed
    assert rows["pick-place/002"].failure_reason == "crashed: RuntimeError: boom"
    assert rows["pick-place/000"].success and rows["pick-place/003"].success


def test_worker_killed_on_every_retry_becomes_a_failure_row(
    tmp_path: Path, ray_instance: object
) -> None:
    report = run_sweep(SYMBOLIC, tmp_path, runner=_always_dies, executor=RayExecutor(max_retries=1))
    rows = {r.scene: r for r in report.rows}
    assert len(rows) == 4
    dead = rows["pick-place/001"]
    assert dead.crashed and not dead.success
    assert dead.failure_reason.startswith(WORKER_DIED)
    assert "Ray retried it 1 times" in dead.failure_reason
    assert all(rows[s].success for s in ("pick-place/000", "pick-place/002", "pick-place/003"))


def test_interrupted_ray_sweep_resumes_with_the_local_executor(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ray_instance: object
) -> None:
    append = ResultsFile.append
    count = {"rows": 0}

    def interrupt_after_two(self: ResultsFile, row: ResultRow) -> None:
        append(self, row)
        count["rows"] += 1
        if count["rows"] == 2:
            raise KeyboardInterrupt  # Ctrl-C while Ray tasks are in flight

    monkeypatch.setattr(ResultsFile, "append", interrupt_after_two)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(SYMBOLIC, tmp_path, executor=RayExecutor(), progress=False)
    monkeypatch.setattr(ResultsFile, "append", append)
    assert len(read_rows(tmp_path / "results.csv")) == 2
    resumed = run_sweep(SYMBOLIC, tmp_path, executor=LocalExecutor(0), progress=False)
    assert (resumed.ran, resumed.resumed) == (2, 2)
    assert len(resumed.rows) == 4 and all(r.success for r in resumed.rows)
    assert ray.is_initialized()  # an instance the caller started is left running


def _cube(x: int) -> int:
    return x**3


def test_generic_tasks_with_several_cpus_each(ray_instance: object) -> None:
    """The interface training reuses: any picklable function, tasks reserving 2 CPUs."""
    got: list[int] = []
    RayExecutor(task_cpus=2).run(_cube, list(range(5)), got.append, lambda t, r: -1)
    assert sorted(got) == [0, 1, 8, 27, 64]
