"""Fast Downward's search binary and driver: the search configurations, where the programs
are, and what their exit codes and outputs mean.

`search_sas` runs the C++ search binary on a SAS task given as text (on stdin; the plan
comes back through a pipe), which is all the fast path needs after grounding in-process
(`utamp_gym.planning.state_planner`). `solve_with_driver` runs the official driver script
for comparison.
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
import time
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

from utamp_gym.deadline import Deadline, check_timeout
from utamp_gym.errors import PddlError, PlanningError, UnknownNameError
from utamp_gym.planning.processes import run, tail

# "lama-first" is the driver alias from up_fast_downward/downward/driver/aliases.py
# (Fast Downward 26.6), with spaces and newlines stripped exactly as the driver does.
SEARCH_ARGS: dict[str, tuple[str, ...]] = {
    "lama-first": (
        "--search",
        "let(hlm,eval_modify_costs(landmark_sum(lm_factory=lm_reasonable_orders_hps(lm_rhw()),"
        "pref=false),cost_type=one),let(hff,eval_modify_costs(ff(),cost_type=one),"
        "lazy_greedy([hff,hlm],preferred=[hff,hlm],cost_type=one,reopen_closed=false)))",
    ),
    "astar-lmcut": ("--search", "astar(lmcut())"),
    "astar-blind": ("--search", "astar(blind())"),
}
SEARCH_CONFIGS: tuple[str, ...] = tuple(SEARCH_ARGS)
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

TRANSLATOR_UNSOLVABLE = re.compile(r"^(.*)! Generating unsolvable task\.\.\.$", re.M)
_EXPANDED = re.compile(r"\] Expanded (\d+) state\(s\)\.")
_COST = re.compile(r"^; cost = (\d+)", re.M)
_DRIVER_TRANSLATE_TIME = re.compile(r"^Done! \[[\d.]+s CPU, ([\d.]+)s wall-clock\]", re.M)
_SEARCH_TOTAL_TIME = re.compile(r"\] Total time: ([\d.]+)s")


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


def translator_reason(message: str) -> str:
    return f"goal unreachable (proved unsolvable by translator: {message.strip().lower()})"


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
        by_translator = TRANSLATOR_UNSOLVABLE.search(stdout)
        reason = (
            translator_reason(by_translator.group(1)) if by_translator else _UNSOLVED_REASONS[code]
        )
        return PlanResult(False, (), None, *times, reason, n_expanded)
    error = PddlError if code == _TRANSLATE_INPUT_ERROR else PlanningError
    raise error(f"{what} failed with exit code {code}:{tail(stderr or stdout)}")


def search_sas(
    sas: str,
    *,
    search: str,
    deadline: Deadline,
    start: float,
    started: Callable[[], object] | None = None,
) -> PlanResult:
    """Run the search binary on a SAS task until `deadline`; times count from `start`;
    `started` is called once the binary runs (`processes.run`).

    Raises `PlanningTimeout` (phase ``search``) if the deadline passes first; the binary's
    process group is killed.
    """
    binary, _ = downward_paths()
    translate_time = time.perf_counter() - start
    deadline.check("search")
    what = f"Fast Downward search '{search}'"
    search_start = time.perf_counter()
    code, stdout, stderr, plan = run(
        [str(binary), *SEARCH_ARGS[search]],
        stdin=sas.encode(),
        timeout=deadline.remaining(),
        what=what,
        limit=deadline.limit,
        plan_pipe=True,
        started=started,
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
    if alias is None and search not in SEARCH_ARGS:
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
            cmd = [sys.executable, str(driver), *map(str, files), *SEARCH_ARGS[search]]
        start = time.perf_counter()
        code, stdout, stderr, _ = run(
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


__all__ = [
    "DEFAULT_SEARCH",
    "SEARCH_ARGS",
    "SEARCH_CONFIGS",
    "TRANSLATOR_UNSOLVABLE",
    "PlanResult",
    "downward_paths",
    "search_sas",
    "solve_with_driver",
    "translator_reason",
]
