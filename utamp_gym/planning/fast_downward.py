"""Fast Downward as a library: PDDL texts in, a plan out.

The fast path (:func:`solve`, and `utamp_gym.planning.state_planner.StatePlanner`) grounds
the task *in this process* and runs only the C++ search binary as a subprocess: it reads the
SAS task on stdin and writes its plan to a pipe, so no file is written. This skips two
Python start-ups and the driver, which dominate the wall time on our small tasks.
:func:`solve_with_driver` runs the official driver script for comparison.

Every subprocess runs in its own session; on time-out, error or interrupt its whole
process group is killed with SIGKILL and reaped, so no planner process outlives a call.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import io
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from functools import lru_cache
from pathlib import Path
from types import FrameType, ModuleType
from typing import NamedTuple

from utamp_gym.deadline import Deadline, check_timeout
from utamp_gym.errors import PddlError, PlanningError, PlanningTimeout, UnknownNameError

__all__ = [
    "DEFAULT_SEARCH",
    "SEARCH_CONFIGS",
    "TRANSLATORS",
    "PlanResult",
    "downward_paths",
    "search_sas",
    "solve",
    "solve_with_driver",
]

# "lama-first" is the driver alias from up_fast_downward/downward/driver/aliases.py
# (Fast Downward 26.6), with spaces and newlines stripped exactly as the driver does.
_SEARCH_ARGS: dict[str, tuple[str, ...]] = {
    "lama-first": (
        "--search",
        "let(hlm,eval_modify_costs(landmark_sum(lm_factory=lm_reasonable_orders_hps(lm_rhw()),"
        "pref=false),cost_type=one),let(hff,eval_modify_costs(ff(),cost_type=one),"
        "lazy_greedy([hff,hlm],preferred=[hff,hlm],cost_type=one,reopen_closed=false)))",
    ),
    "astar-lmcut": ("--search", "astar(lmcut())"),
    "astar-blind": ("--search", "astar(blind())"),
}
SEARCH_CONFIGS: tuple[str, ...] = tuple(_SEARCH_ARGS)
"""Valid ``search`` names for :func:`solve` (``lama-first``: satisficing; ``astar-*``: optimal)."""
DEFAULT_SEARCH = "astar-blind"
"""Optimal plans (lama-first's are up to 3x longer on five objects: 36 steps against 12,
which triples a physics episode), and of the optimal configurations the fastest on every
suite task measured (`benchmarks/planning.py --sections search`): these tasks are small,
so LM-cut's per-state cost outweighs the states it saves. Median CPU per search, five
objects: UTAMP-2 23 ms blind vs 36 ms LM-cut; UTAMP-1 0.22 s vs 1.06 s; noisy affordances
(some unsolvable) 23 ms vs 35 ms."""

# Exit codes of the search binary / driver (driver/returncodes.py). Note the order:
# 11 means *proved* unsolvable, 12 means an incomplete search gave up.
_SOLVED_CODES = {0, 1, 2, 3}  # 1-3: plan found, then out of memory/time (anytime search)
_UNSOLVED_REASONS = {
    11: "search space exhausted: task unsolvable",
    12: "search space exhausted by an incomplete search: task may still be solvable",
    13: "no plan within the cost bound",
}
_TRANSLATE_INPUT_ERROR = 31

_TRANSLATOR_UNSOLVABLE = re.compile(r"^(.*)! Generating unsolvable task\.\.\.$", re.M)
_EXPANDED = re.compile(r"\] Expanded (\d+) state\(s\)\.")
_COST = re.compile(r"^; cost = (\d+)", re.M)
_DRIVER_TRANSLATE_TIME = re.compile(r"^Done! \[[\d.]+s CPU, ([\d.]+)s wall-clock\]", re.M)
_SEARCH_TOTAL_TIME = re.compile(r"\] Total time: ([\d.]+)s")

_translate_lock = threading.Lock()  # the translator keeps its options in a module global


class PlanResult(NamedTuple):
    """Outcome of one planner call.

    ``plan`` holds lower-case ground actions such as ``(pick-up a)``; ``reason`` says why
    ``solved`` is False. Times are wall-clock seconds. For :func:`solve_with_driver`
    ``planning_time_s`` is the driver's wall time (interpreter start-ups included) and
    the component times are those the translator and search report themselves.
    """

    solved: bool
    plan: tuple[str, ...]
    cost: int | None
    planning_time_s: float
    translate_time_s: float | None
    search_time_s: float | None
    reason: str | None = None
    expanded: int | None = None


@lru_cache(maxsize=1)
def downward_paths() -> tuple[Path, Path]:
    """Return (search binary, driver script) shipped by up-fast-downward.

    Located via ``find_spec`` because importing ``up_fast_downward`` needs
    unified_planning, which this package does not depend on.
    """
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        raise PlanningError(
            "Fast Downward not found: the 'up-fast-downward' distribution is not installed "
            "(pip install 'up-fast-downward>=1,<2')"
        )
    root = Path(next(iter(spec.submodule_search_locations))) / "downward"
    binary = root / "builds" / "release" / "bin" / "downward"
    driver = root / "fast-downward.py"
    for path, what in ((binary, "search binary"), (driver, "driver script")):
        if not path.is_file():
            raise PlanningError(
                f"Fast Downward {what} missing at {path}; reinstall up-fast-downward"
            )
    return binary, driver


@lru_cache(maxsize=1)
def _translator() -> dict[str, ModuleType]:
    """Import the translator modules once (distribution ``fast-downward.translate``)."""
    names = (
        "main",
        "normalize",
        "options",
        "pddl_parser",
        "pddl_parser.lisp_parser",
        "pddl_parser.parsing_functions",
    )
    try:
        return {n: importlib.import_module(f"fast_downward.translate.{n}") for n in names}
    except ImportError as e:
        raise PlanningError(
            "Fast Downward translator not found: install the 'fast-downward.translate' "
            f"distribution (module fast_downward.translate): {e}"
        ) from e


@lru_cache(maxsize=1)
def _default_translate_options() -> argparse.Namespace:
    """The translator's defaults (what the driver uses); the file names are unused."""
    return _translator()["options"].parse_args(["domain.pddl", "problem.pddl"])


def _translate(domain: str, problem: str, max_time_s: float) -> tuple[str | None, str | None]:
    """Translate PDDL texts to SAS text in-process.

    Returns ``(sas, None)``, or ``(None, reason)`` if the translator proved the task
    unsolvable. Options are set explicitly on every call and the previous global restored,
    and the translator's progress output is captured, so calls are re-entrant.
    """
    tr = _translator()
    opts = argparse.Namespace(**vars(_default_translate_options()))
    # Invariant synthesis is the only translator step with its own limit (CPU s, int).
    opts.invariant_generation_max_time = max(1, min(300, math.ceil(max_time_s)))
    chatter = io.StringIO()
    with _translate_lock:
        saved = tr["options"].options
        tr["options"].options = opts
        tr["main"].simplified_effect_condition_counter = 0  # statistics globals
        tr["main"].added_implied_precondition_counter = 0
        try:
            with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
                parsed = []
                for label, text in (("domain", domain), ("problem", problem)):
                    try:
                        parsed.append(
                            tr["pddl_parser.lisp_parser"].parse_nested_list(text.splitlines())
                        )
                    except tr["pddl_parser"].ParseError as e:
                        raise tr["pddl_parser"].ParseError(f"{label}: {e}") from e
                task = tr["pddl_parser.parsing_functions"].parse_task(*parsed)
                tr["normalize"].normalize(task)
                sas_task = tr["main"].pddl_to_sas(task)
                out = io.StringIO()
                sas_task.output(out)
        except (tr["pddl_parser"].ParseError, SystemExit, AssertionError, KeyError) as e:
            # SystemExit: the translator exits on unsupported PDDL; never let it end the caller.
            raise PddlError(
                f"Fast Downward translator rejected the PDDL: {e!s}{_tail(chatter.getvalue())}"
            ) from e
        except Exception as e:
            raise PlanningError(f"Fast Downward translator failed: {e!r}") from e
        finally:
            tr["options"].options = saved
    unsolvable = _TRANSLATOR_UNSOLVABLE.search(chatter.getvalue())
    if unsolvable:
        return None, _translator_reason(unsolvable.group(1))
    return out.getvalue(), None


def _translator_reason(message: str) -> str:
    return f"goal unreachable (proved unsolvable by translator: {message.strip().lower()})"


def _tail(text: str, lines: int = 15) -> str:
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


def _run(
    cmd: Sequence[str],
    *,
    stdin: bytes | None,
    timeout: float,
    what: str,
    limit: float,
    cwd: str | None = None,
    plan_pipe: bool = False,
) -> tuple[int, str, str, str | None]:
    """Run ``cmd`` in its own session, feeding `stdin`; kill its process group on time-out,
    error or interrupt. Returns (exit code, stdout, stderr, plan): with `plan_pipe`, the
    search binary writes its plan to a pipe (``--internal-plan-file /dev/fd/N``), so no
    file is written at all; otherwise plan is None."""
    cmd, plan_r, plan_w, roomy = list(cmd), -1, -1, False
    if plan_pipe:
        plan_r, plan_w, roomy = _roomy_pipe()
        cmd += ["--internal-plan-file", f"/dev/fd/{plan_w}"]
    chunks: list[bytes] = []
    reader = None
    try:
        held = _HeldSigint()
        try:
            proc = subprocess.Popen(
                cmd,
                cwd=cwd,
                stdin=subprocess.DEVNULL if stdin is None else subprocess.PIPE,
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


def _parse_plan(text: str | None) -> tuple[tuple[str, ...], int | None]:
    """The action lines of a plan file and the cost from its trailing comment."""
    if not text:
        raise PlanningError("Fast Downward reported a plan but wrote none")
    plan = tuple(
        ln.strip().lower() for ln in text.splitlines() if ln.strip() and not ln.startswith(";")
    )
    cost = _COST.search(text)
    return plan, (int(cost.group(1)) if cost else None)


def _interpret(
    code: int,
    stdout: str,
    stderr: str,
    plan_text: str | None,
    what: str,
    times: tuple[float, float | None, float | None],
) -> PlanResult:
    """Turn an exit code and the outputs into a PlanResult (or raise PlanningError)."""
    expanded = _EXPANDED.findall(stdout)
    n_expanded = int(expanded[-1]) if expanded else None
    if code in _SOLVED_CODES:
        plan, cost = _parse_plan(plan_text)
        return PlanResult(True, plan, cost, *times, None, n_expanded)
    if code in _UNSOLVED_REASONS:
        by_translator = _TRANSLATOR_UNSOLVABLE.search(stdout)
        reason = (
            _translator_reason(by_translator.group(1)) if by_translator else _UNSOLVED_REASONS[code]
        )
        return PlanResult(False, (), None, *times, reason, n_expanded)
    error = PddlError if code == _TRANSLATE_INPUT_ERROR else PlanningError
    raise error(f"{what} failed with exit code {code}:{_tail(stderr or stdout)}")


TRANSLATORS = ("utamp", "fd")
"""``utamp``: our relaxed-reachability grounder + SAS writer (fast path, default);
``fd``: Fast Downward's own Python translator, run in-process."""


def solve(
    domain: str,
    problem: str,
    *,
    search: str = DEFAULT_SEARCH,
    timeout: float = 30.0,
    translator: str = "utamp",
    exclude: frozenset[str] = frozenset(),
) -> PlanResult:
    """Plan for PDDL ``domain``/``problem`` texts: in-process translation, then the binary.

    ``search`` is one of :data:`SEARCH_CONFIGS`, ``translator`` one of :data:`TRANSLATORS`.
    ``exclude``: ground actions (PDDL text) the plan must not use (our translator only).
    ``timeout`` (s) bounds parsing, grounding, SAS writing and search; exceeding it raises
    :class:`PlanningTimeout` naming the phase. (Fast Downward's own translator cannot be
    interrupted: with ``translator="fd"`` the limit is checked when it returns.) An
    unsolvable task returns ``solved=False`` with a ``reason``; bad PDDL raises
    :class:`PddlError`.
    """
    if search not in _SEARCH_ARGS:
        raise UnknownNameError("search configuration", search, SEARCH_CONFIGS)
    if translator not in TRANSLATORS:
        raise UnknownNameError("translator", translator, TRANSLATORS)
    if exclude and translator != "utamp":
        raise ValueError("exclude needs translator='utamp'")
    deadline = Deadline.after(timeout)
    if translator == "utamp":
        from utamp_gym.planning.state_planner import StatePlanner, problem_atoms
        from utamp_gym.symbolic.pddl import cached_domain, parse_problem

        dom = cached_domain(domain, "domain")
        prob = parse_problem(problem, source="problem")
        deadline.check("grounding")
        planner = StatePlanner(dom, search=search, timeout=timeout)
        return planner.plan(
            *problem_atoms(dom, prob), exclude=exclude, deadline=deadline, source=prob.source
        )
    start = time.perf_counter()
    sas, reason = _translate(domain, problem, timeout)
    translate_time = time.perf_counter() - start
    if reason is not None:
        return PlanResult(False, (), None, translate_time, translate_time, 0.0, reason, None)
    assert sas is not None
    if deadline.expired():
        raise PlanningTimeout(
            f"translation alone took {translate_time:.3f} s, using up the time limit of "
            f"{timeout:g} s; the search was not started",
            phase="grounding",
        )
    return search_sas(sas, search=search, deadline=deadline, start=start)


def search_sas(sas: str, *, search: str, deadline: Deadline, start: float) -> PlanResult:
    """Run the search binary on a SAS task until `deadline`; times count from `start`.

    Raises `PlanningTimeout` (phase ``search``) if the deadline passes first; the binary's
    process group is killed.
    """
    binary, _ = downward_paths()
    translate_time = time.perf_counter() - start
    deadline.check("search")
    what = f"Fast Downward search '{search}'"
    search_start = time.perf_counter()
    code, stdout, stderr, plan = _run(
        [str(binary), *_SEARCH_ARGS[search]],
        stdin=sas.encode(),
        timeout=deadline.remaining(),
        what=what,
        limit=deadline.limit,
        plan_pipe=True,
    )
    search_time = time.perf_counter() - search_start
    times = (time.perf_counter() - start, translate_time, search_time)
    return _interpret(code, stdout, stderr, plan, what, times)


def solve_with_driver(
    domain_path: str | os.PathLike[str],
    problem_path: str | os.PathLike[str],
    *,
    search: str = DEFAULT_SEARCH,
    alias: str | None = None,
    timeout: float = 30.0,
) -> PlanResult:
    """Plan with the official ``fast-downward.py`` driver (for benchmarks).

    It runs the same search arguments as ``solve(search=...)``, or ``--alias ALIAS`` if
    given. Same result and time-out semantics as :func:`solve`; reads PDDL files.
    """
    check_timeout(timeout)
    if alias is None and search not in _SEARCH_ARGS:
        raise UnknownNameError("search configuration", search, SEARCH_CONFIGS)
    _, driver = downward_paths()
    files = [Path(p).resolve() for p in (domain_path, problem_path)]
    for path in files:
        if not path.is_file():
            raise PddlError(f"PDDL file not found: {path}")
    import tempfile  # only the driver needs a working directory

    with tempfile.TemporaryDirectory(prefix="utamp_fd_driver_") as workdir:
        if alias is not None:
            what = f"Fast Downward driver (--alias {alias})"
            cmd = [sys.executable, str(driver), "--alias", alias, *map(str, files)]
        else:
            what = f"Fast Downward driver ({search})"
            cmd = [sys.executable, str(driver), *map(str, files), *_SEARCH_ARGS[search]]
        start = time.perf_counter()
        code, stdout, stderr, _ = _run(
            cmd, stdin=None, timeout=timeout, what=what, limit=timeout, cwd=workdir
        )
        wall = time.perf_counter() - start
        translate = _DRIVER_TRANSLATE_TIME.search(stdout)
        search = _SEARCH_TOTAL_TIME.findall(stdout)
        times = (
            wall,
            float(translate.group(1)) if translate else None,
            float(search[-1]) if search else None,
        )
        plan_file = Path(workdir, "sas_plan")
        plan = plan_file.read_text() if plan_file.is_file() else None
        return _interpret(code, stdout, stderr, plan, what, times)
