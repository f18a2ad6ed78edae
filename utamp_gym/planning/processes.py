"""Running Fast Downward's processes: each in its own session, killed with its whole process
group on time-out, error or interrupt, so no planner process outlives a call.

`run` feeds a command its input and, for the search binary, reads its plan from a pipe
(``--internal-plan-file /dev/fd/N``), so no file is written. A Ctrl-C is never lost: one
that lands while a process starts is held until the caller holds the process to kill.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from types import FrameType

from utamp_gym.errors import PlanningTimeout


def tail(text: str, lines: int = 15) -> str:
    """The last `lines` lines of a process's output, on lines of their own after a newline."""
    kept = text.strip().splitlines()[-lines:]
    return ("\n" + "\n".join(kept)) if kept else ""


def _kill_group(proc: subprocess.Popen) -> None:
    """SIGKILL the process group of an unreaped ``start_new_session`` child and reap it."""
    if proc.returncode is None:  # not reaped yet, so its process-group id is still ours
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        # grandchildren (the driver's search binary) die asynchronously: give them a moment
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline:
            try:
                os.killpg(proc.pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.002)


_PLAN_PIPE_BYTES = 1 << 20  # a plan pipe this large never fills up (plans take kilobytes)


def _drain(fd: int, chunks: list[bytes]) -> None:
    """Read `fd` to its end."""
    while chunk := os.read(fd, 65536):
        chunks.append(chunk)


def _in_memory(data: bytes | None) -> int:
    """A file descriptor of an in-memory file holding `data`, read from its start (Linux's
    memfd), or -1 (no data, or no memfd here: the caller pipes it).

    Why: `subprocess` feeds a pipe a few kilobytes per wake-up of the child, so a 1 MB SAS
    task (UTAMP-1's) took a search 30 s and more to receive on a machine under load, where
    it reads it in well under a second from a file."""
    if data is None or not hasattr(os, "memfd_create"):
        return -1
    fd = os.memfd_create("utamp-input")
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
        os.lseek(fd, 0, os.SEEK_SET)
    except BaseException:
        os.close(fd)
        raise
    return fd


def _roomy_pipe() -> tuple[int, int, bool]:
    """(read end, write end, whether the pipe holds `_PLAN_PIPE_BYTES`). If it does, the
    plan is read after the search ends; otherwise a thread must drain it meanwhile."""
    r, w = os.pipe()
    try:
        import fcntl

        roomy = fcntl.fcntl(w, fcntl.F_SETPIPE_SZ, _PLAN_PIPE_BYTES) >= _PLAN_PIPE_BYTES
    except (ImportError, AttributeError, OSError):  # not Linux, or pipe-max-size is smaller
        roomy = False
    return r, w, roomy


#: s between two returns to Python while a subprocess runs: a Ctrl-C whose C handler ran in
#: another thread (the main thread had SIGINT blocked, as `subprocess` does around vfork)
#: is only acted on by the main thread once it runs Python code again
_WAIT_SLICE = 0.1


class _HeldSigint:
    """Hold Ctrl-C back while a subprocess starts, until `release`.

    A KeyboardInterrupt raised inside `subprocess.Popen` after the fork loses the child: no
    `Popen` object comes back, so nothing kills it (its pid is gone with the exception). In
    the main thread, with a Python SIGINT handler, this swaps in one that only notes the
    signal; `release` puts the handler back and runs it if a signal came meanwhile (the
    default handler raises KeyboardInterrupt), once the caller holds the process to kill."""

    def __init__(self) -> None:
        self._previous: Callable[[int, FrameType | None], object] | None = None
        self._frames: list[FrameType | None] = []
        if threading.current_thread() is threading.main_thread():
            handler = signal.getsignal(signal.SIGINT)
            if callable(handler):
                self._previous = handler
                signal.signal(signal.SIGINT, lambda _, frame: self._frames.append(frame))

    def release(self) -> None:
        previous, self._previous = self._previous, None
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
            if self._frames:
                previous(signal.SIGINT, self._frames[0])


def _communicate(
    proc: subprocess.Popen, stdin: bytes | None, timeout: float
) -> tuple[bytes, bytes]:
    """`proc.communicate(stdin, timeout)`, in slices of `_WAIT_SLICE` s (see there)."""
    end = time.monotonic() + max(timeout, 0.0)
    while True:
        try:
            return proc.communicate(
                stdin, timeout=min(_WAIT_SLICE, max(end - time.monotonic(), 0.0))
            )
        except subprocess.TimeoutExpired:
            if time.monotonic() >= end:
                raise
            stdin = None  # the rest of the input is sent by the next call


def run(
    cmd: Sequence[str],
    *,
    stdin: bytes | None,
    timeout: float,
    what: str,
    limit: float,
    cwd: str | None = None,
    plan_pipe: bool = False,
    started: Callable[[], object] | None = None,
) -> tuple[int, str, str, str | None]:
    """Run ``cmd`` in its own session, feeding `stdin`; kill its process group on time-out,
    error or interrupt. Returns (exit code, stdout, stderr, plan): with `plan_pipe`, the
    search binary writes its plan to a pipe (``--internal-plan-file /dev/fd/N``), so no
    file is written at all; otherwise plan is None. `started` is called once the process
    runs, before waiting for it (work to do meanwhile)."""
    cmd, plan_r, plan_w, roomy = list(cmd), -1, -1, False
    if plan_pipe:
        plan_r, plan_w, roomy = _roomy_pipe()
        cmd += ["--internal-plan-file", f"/dev/fd/{plan_w}"]
    chunks: list[bytes] = []
    reader = None
    source = _in_memory(stdin)  # the input as a file, or -1: fed through a pipe
    if source >= 0:
        stdin = None
    try:
        held = _HeldSigint()
        try:
            proc = subprocess.Popen(
                cmd,
                cwd=cwd,
                stdin=source
                if source >= 0
                else subprocess.DEVNULL
                if stdin is None
                else subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                pass_fds=(plan_w,) if plan_pipe else (),
                start_new_session=True,
            )
        except BaseException:
            held.release()
            raise
        with proc:
            try:
                held.release()  # a Ctrl-C during the start is raised here: the group is killed
                if plan_pipe:
                    os.close(plan_w)
                    plan_w = -1
                    if not roomy:
                        reader = threading.Thread(target=_drain, args=(plan_r, chunks), daemon=True)
                        reader.start()
                if started is not None:
                    started()
                try:
                    out, err = _communicate(proc, stdin, timeout)
                except subprocess.TimeoutExpired:
                    _kill_group(proc)
                    raise PlanningTimeout(
                        f"{what} exceeded the time limit of {limit:g} s; its process group "
                        f"(pid {proc.pid}) was killed",
                        phase="search",
                    ) from None
            finally:
                _kill_group(proc)  # no-op once reaped; covers KeyboardInterrupt and errors
    finally:
        if source >= 0:
            os.close(source)
        if plan_w >= 0:
            os.close(plan_w)
        if reader is not None:
            reader.join()  # the child is gone, so its end of the pipe is closed
        elif plan_r >= 0 and plan_w < 0:
            _drain(plan_r, chunks)  # the child is gone: all it wrote is in the pipe
        if plan_r >= 0:
            os.close(plan_r)
    plan = b"".join(chunks).decode("utf-8", "replace") if plan_pipe else None
    decode = lambda b: b.decode("utf-8", "replace")  # noqa: E731
    return proc.returncode, decode(out), decode(err), plan


__all__ = ["run", "tail"]
