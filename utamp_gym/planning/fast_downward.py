"""Fast Downward as a library: PDDL texts in, a plan out.

The fast path (:func:`solve`, and `utamp_gym.planning.state_planner.StatePlanner`) grounds
the task *in this process* and runs only the C++ search binary as a subprocess: it reads the
SAS task on stdin and writes its plan to a pipe, so no file is written. This skips two
Python start-ups and the driver, which dominate the wall time on our small tasks.
:func:`solve_with_driver` runs the official driver script for comparison.

Every subprocess runs in its own session; on time-out, error or interrupt its whole
process group is killed with SIGKILL and reaped, so no planner process outlives a call
(`utamp_gym.planning.processes`). The search binary and the driver live in
`utamp_gym.planning.downward`, Fast Downward's own translator in
`utamp_gym.planning.fd_translate`; this module puts them together behind `solve`.
"""

from __future__ import annotations

import time

from utamp_gym.deadline import Deadline
from utamp_gym.errors import PlanningTimeout, UnknownNameError
from utamp_gym.planning.downward import (
    DEFAULT_SEARCH,
    SEARCH_ARGS,
    SEARCH_CONFIGS,
    PlanResult,
    downward_paths,
    search_sas,
    solve_with_driver,
)
from utamp_gym.planning.fd_translate import translate
from utamp_gym.planning.state_planner import StatePlanner, problem_atoms
from utamp_gym.symbolic.pddl import cached_domain, parse_problem

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
    if search not in SEARCH_ARGS:
        raise UnknownNameError("search configuration", search, SEARCH_CONFIGS)
    if translator not in TRANSLATORS:
        raise UnknownNameError("translator", translator, TRANSLATORS)
    if exclude and translator != "utamp":
        raise ValueError("exclude needs translator='utamp'")
    deadline = Deadline.after(timeout)
    if translator == "utamp":
        dom = cached_domain(domain, "domain")
        prob = parse_problem(problem, source="problem")
        deadline.check("grounding")
        planner = StatePlanner(dom, search=search, timeout=timeout)
        return planner.plan(
            *problem_atoms(dom, prob), exclude=exclude, deadline=deadline, source=prob.source
        )
    start = time.perf_counter()
    sas, reason = translate(domain, problem, timeout)
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
