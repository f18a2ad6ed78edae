"""Run many independent tasks on this machine or on a Ray cluster, behind one interface.

An executor runs ``fn(task)`` for every task and calls ``record(result)`` on the calling
thread as each one finishes (completion order), exactly once per task; a task whose
function raised, or whose worker process died for good, is recorded as
``failed(task, reason)`` instead, so no task is ever lost. `utamp eval` runs one scene ×
method × seed per task; `utamp train --seeds K` can run one training seed per task.

* `LocalExecutor`: spawn-started worker processes (`ProcessPoolExecutor`), at most one
  task per worker in flight, so when a worker dies (`BrokenProcessPool`) the suspects are
  known: each is re-run alone in a fresh pool and the one that kills it again is recorded
  as failed.
* `RayExecutor`: every task is a Ray task (``max_retries``: Ray re-runs a task whose
  worker died); results stream back with `ray.wait`. It connects to a given address or
  ``RAY_ADDRESS``, else starts a local Ray instance and shuts it down afterwards. Ray is
  the optional extra ``utamp-gym[ray]`` and is imported only here, only when used.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Protocol, TypeVar

from utamp_gym.errors import UnknownNameError, UtampError
from utamp_gym.extras import MissingExtraError

EXECUTORS = ("local", "ray")
WORKER_DIED = "crashed: the worker process died (killed or crashed hard) while running this"
RAY_RETRIES = 3  # Ray's own default for tasks
RAY_MIN_INFLIGHT = 64  # tasks submitted ahead of the results (at least 4 per cluster CPU)
RAY_PROBE_TIMEOUT_S = 5.0  # ray.init itself waits minutes for an unreachable cluster

T = TypeVar("T")
R = TypeVar("R")


class Executor(Protocol):
    """Runs ``fn`` on every task; `record` gets each result (or ``failed(task, reason)``)."""

    def run(
        self,
        fn: Callable[[T], R],
        tasks: Sequence[T],
        record: Callable[[R], None],
        failed: Callable[[T, str], R],
    ) -> None: ...


def crash_reason(exc: BaseException) -> str:
    """The failure reason of a task whose function raised `exc`."""
    return f"crashed: {type(exc).__name__}: {exc}"


@dataclass(frozen=True)
class LocalExecutor:
    """Worker processes on this machine: `workers` of them (None: CPU count; 0: in-process)."""

    workers: int | None = None

    def run(
        self,
        fn: Callable[[T], R],
        tasks: Sequence[T],
        record: Callable[[R], None],
        failed: Callable[[T, str], R],
    ) -> None:
        workers = (os.cpu_count() or 1) if self.workers is None else self.workers
        if workers <= 0:
            for task in tasks:
                try:
                    result = fn(task)
                except Exception as exc:
                    result = failed(task, crash_reason(exc))
                record(result)
            return
        workers = min(workers, len(tasks))
        pending = deque(tasks)
        while pending:
            suspects = _pool_pass(pending, workers, fn, record, failed)
            if len(suspects) == 1:
                record(failed(suspects[0], WORKER_DIED))
                continue
            for task in suspects:  # find the culprit: each suspect alone
                if _pool_pass(deque([task]), 1, fn, record, failed):
                    record(failed(task, WORKER_DIED))


def _pool_pass(
    tasks: deque[T],
    workers: int,
    fn: Callable[[T], R],
    record: Callable[[R], None],
    failed: Callable[[T, str], R],
) -> list[T]:
    """Run `tasks` in one pool until done or the pool breaks; returns the suspects."""
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    inflight: dict[Future[R], T] = {}
    interrupted = True
    try:
        while tasks or inflight:
            while tasks and len(inflight) < workers:
                task = tasks.popleft()
                try:
                    inflight[pool.submit(fn, task)] = task
                except BrokenProcessPool:
                    tasks.appendleft(task)
                    interrupted = False
                    return list(inflight.values())
            done, _ = wait(inflight, return_when=FIRST_COMPLETED)
            broken = []
            for fut in done:
                task = inflight.pop(fut)
                try:
                    result = fut.result()
                except BrokenProcessPool:
                    broken.append(task)
                    continue
                except Exception as exc:  # fn raised, or its result could not be pickled
                    result = failed(task, crash_reason(exc))
                record(result)
            if broken:
                interrupted = False
                return [*broken, *inflight.values()]
        interrupted = False
        return []
    finally:  # on Ctrl-C do not wait for running tasks
        pool.shutdown(wait=not interrupted, cancel_futures=True)


def import_ray() -> ModuleType:
    """The `ray` module, or a `MissingExtraError` that names the extra to install."""
    try:
        import ray
    except ImportError as exc:
        raise MissingExtraError("--executor ray", "ray", "ray", str(exc)) from None
    return ray


def _probe(address: str) -> None:
    """Fail within seconds if a ``HOST:PORT`` cluster address does not accept connections."""
    host, sep, port = address.rpartition(":")
    if "://" in address or not sep or not port.isdigit():
        return  # "auto", a Ray Client "ray://..." address, ...: left to ray.init
    try:
        socket.create_connection((host, int(port)), timeout=RAY_PROBE_TIMEOUT_S).close()
    except OSError as exc:
        raise UtampError(
            f"cannot reach the Ray cluster at {address!r} ({exc}); start one with "
            "`ray start --head` or check --ray-address / RAY_ADDRESS"
        ) from None


def _call(fn: Callable[[T], R], task: T) -> R:
    """The Ray task body: one generic remote function for every `fn` (sent once, by ref)."""
    return fn(task)


@dataclass(frozen=True)
class RayExecutor:
    """Ray tasks: on `address`, else ``RAY_ADDRESS``, else a new local instance.

    `num_cpus` sizes a new local instance (default: every CPU); it is ignored when
    connecting to a cluster. If Ray is already initialised in this process (a test, a
    benchmark, a notebook), that instance is used and left running. A task whose worker
    dies is re-run by Ray up to `max_retries` times; an exception raised by the task
    itself is not retried (it would raise again). Each task reserves `task_cpus` CPUs
    (an evaluation run is single-threaded; a training run may want more).
    """

    address: str | None = None
    num_cpus: int | None = None
    max_retries: int = RAY_RETRIES
    task_cpus: float = 1.0

    def __post_init__(self) -> None:
        import_ray()  # fail before any work when the extra is missing
        if self.max_retries < 0:
            raise UtampError(f"max_retries must be at least 0, got {self.max_retries}")
        if self.task_cpus <= 0:
            raise UtampError(f"task_cpus must be positive, got {self.task_cpus}")

    def run(
        self,
        fn: Callable[[T], R],
        tasks: Sequence[T],
        record: Callable[[R], None],
        failed: Callable[[T, str], R],
    ) -> None:
        if not tasks:
            return
        ray = import_ray()
        own = not ray.is_initialized()
        if own:
            self._init(ray)
        try:
            self._stream(ray, fn, tasks, record, failed)
        finally:  # also on Ctrl-C: a local instance stops with its workers
            if own:
                ray.shutdown()

    def _init(self, ray: ModuleType) -> None:
        address = self.address or os.environ.get("RAY_ADDRESS") or None
        # "error": Ray warns on stderr at every start about its token authentication (on or
        # off), noise for a command that succeeds
        quiet: dict[str, Any] = {"log_to_driver": False, "logging_level": "error"}
        if address is None:  # "local": never attach to some other `ray start` on this host
            ray.init(address="local", num_cpus=self.num_cpus, include_dashboard=False, **quiet)
            return
        _probe(address)
        try:
            ray.init(address=address, **quiet)
        except (ConnectionError, ValueError, RuntimeError) as exc:
            hint = ""
            if os.environ.get("RAY_AUTH_MODE", "").lower() != "token":
                hint = (
                    "; if the cluster uses token authentication (Ray 2.60's `ray start "
                    "--head` enables it when ~/.ray/auth_token exists), copy the head's "
                    "~/.ray/auth_token here and set RAY_AUTH_MODE=token"
                )
            raise UtampError(
                f"cannot connect to the Ray cluster at {address!r}: {exc}{hint}"
            ) from None

    def _stream(
        self,
        ray: ModuleType,
        fn: Callable[[T], R],
        tasks: Sequence[T],
        record: Callable[[R], None],
        failed: Callable[[T, str], R],
    ) -> None:
        remote = ray.remote(_call).options(num_cpus=self.task_cpus, max_retries=self.max_retries)
        fn_ref = ray.put(fn)
        slots = ray.cluster_resources().get("CPU", 1) / self.task_cpus
        ahead = max(RAY_MIN_INFLIGHT, 4 * int(slots))
        todo: Iterator[T] = iter(tasks)
        pending: dict[Any, T] = {}

        def submit() -> None:
            for task in todo:
                pending[remote.remote(fn_ref, task)] = task
                if len(pending) >= ahead:
                    return

        try:
            submit()
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1)
                for ref in done:
                    task = pending.pop(ref)
                    record(self._result(ray, ref, task, failed))
                submit()
        except BaseException:  # Ctrl-C or a failing `record`: stop the runs in flight
            for ref in pending:
                ray.cancel(ref, force=True)
            raise

    def _result(self, ray: ModuleType, ref: Any, task: T, failed: Callable[[T, str], R]) -> R:
        try:
            return ray.get(ref)  # type: ignore[no-any-return]
        except ray.exceptions.RayTaskError as exc:  # the task itself raised
            cause = exc.cause if isinstance(exc.cause, BaseException) else exc
            return failed(task, crash_reason(cause))
        except ray.exceptions.RayError as exc:  # worker or node died after every retry
            return failed(
                task,
                f"{WORKER_DIED} ({type(exc).__name__}; Ray retried it {self.max_retries} times)",
            )


def make_executor(
    name: str,
    *,
    workers: int | None = None,
    ray_address: str | None = None,
    max_retries: int = RAY_RETRIES,
    task_cpus: float = 1.0,
) -> Executor:
    """The executor called `name` (``local`` or ``ray``); `workers` sizes a local Ray too,
    `max_retries` and `task_cpus` are Ray's (see `RayExecutor`)."""
    if name == "local":
        if ray_address:
            raise UtampError("--ray-address needs --executor ray")
        return LocalExecutor(workers)
    if name == "ray":
        if workers is not None and workers < 1:
            raise UtampError(f"--workers must be at least 1 with --executor ray, got {workers}")
        return RayExecutor(ray_address, workers, max_retries, task_cpus)
    raise UnknownNameError("executor", name, EXECUTORS)
