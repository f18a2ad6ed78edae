"""`StatePlanner`: plan from any state of a task, grounding each task once.

Why: closed-loop execution re-plans from the current state many times per episode, and all
the states of an episode share the domain, the objects, the static atoms and the goal, so
their SAS tasks differ only in the initial state. The planner grounds (relaxed reachability
from the first state it sees) and writes the SAS task once per key (domain, objects, static
atoms, goal), then writes only the initial state on each call and runs the search binary.

A cached task is only used for a state it covers (`SasTask.covers`): every atom of the state
is one the first grounding reached, the atoms no action changes agree, and every
exactly-one group has exactly one true atom. States reached by actions from the first state
always are; a perceived state after a physical surprise may not be, and is then grounded
anew (that task is cached as well). A wrong SAS file is never written.

The cache lives in the planner instance, bounded (least recently used keys are dropped);
the grounder keeps its join orders between calls.
"""

from __future__ import annotations

import contextlib
import gc
import time
from collections import OrderedDict
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping
from types import MappingProxyType
from typing import NamedTuple

from utamp_gym.deadline import Deadline, check_timeout
from utamp_gym.errors import PddlError, UnknownNameError
from utamp_gym.planning.downward import DEFAULT_SEARCH, SEARCH_CONFIGS, PlanResult, search_sas
from utamp_gym.planning.postprocess import eliminate
from utamp_gym.planning.sas import SasTask, build_sas
from utamp_gym.symbolic.pddl import Atom, Domain, Literal, Problem, cached_domain
from utamp_gym.symbolic.problem import domain_text
from utamp_gym.symbolic.reach import Grounder

#: searches whose plans greedy action elimination can shorten (the others are optimal)
SATISFICING_SEARCHES = frozenset({"lama-first"})
UNREACHABLE = "goal unreachable (proved unsolvable by relaxed reachability)"


def parse_atom(text: str) -> Atom:
    """``"(oc on slot1 tray)"`` -> ``Atom("oc", ("on", "slot1", "tray"))`` (lower-cased)."""
    body = text.strip()
    if body[:1] == "(" and body[-1:] == ")" and body.count("(") == 1 and body.count(")") == 1:
        words = body[1:-1].lower().split()
        if words:
            return Atom(words[0], tuple(words[1:]))
    raise ValueError(f"expected a ground atom like '(pred arg ...)', got {text!r}")


def parse_literal(text: str) -> Literal:
    """A ground atom or ``"(not (pred arg ...))"``."""
    body = text.strip()
    head = body[1:].lstrip().lower()
    if head.startswith("not") and head[3:].lstrip().startswith("("):
        inner = head[3:].strip()
        if not inner.endswith("))"):
            raise ValueError(f"expected '(not (pred arg ...))', got {text!r}")
        return Literal(parse_atom(inner[:-1]), positive=False)
    return Literal(parse_atom(body))


def action_name(action: str) -> str:
    """``"(pick-support  A b)"`` -> ``"pick-support a b"``: the form the SAS task uses."""
    return " ".join(action.strip().strip("()").lower().split())


@contextlib.contextmanager
def paused_gc() -> Iterator[Callable[[], None]]:
    """No cyclic garbage collection inside: grounding builds thousands of tuples and dicts
    and no cycles, and each collection the allocations set off would walk them in vain.

    Yields `resume`, which ends the pause early: the collection the pause's allocations set
    off then comes at the next allocation (`StatePlanner.plan` resumes once the search
    process has started, so that collection runs while the search does)."""
    if not gc.isenabled():
        yield _nothing
        return
    gc.disable()
    try:
        yield gc.enable
    finally:
        gc.enable()


def _nothing() -> None:
    """`paused_gc`'s `resume` when the collector was off already."""


class CacheInfo(NamedTuple):
    """Counters of a `StatePlanner`."""

    hits: int  # calls answered from a cached task
    groundings: int  # tasks grounded: the first state of a key, or one no cached task covers
    uncovered: int  # of these, states that their key's cached tasks did not cover
    tasks: int  # tasks held now


class _KeyTasks:
    """The tasks grounded for one key (most recently used first)."""

    __slots__ = ("goal", "static", "tasks")

    def __init__(self, static: frozenset[Atom], goal: tuple[Literal, ...]) -> None:
        self.static = static
        self.goal = goal
        self.tasks: list[tuple[SasTask, frozenset[Atom]]] = []  # (task, fixed)


class StatePlanner:
    """Plans with Fast Downward from states given as atoms, caching the grounded task.

    `domain` is a packaged domain name (``"utamp2"``, ``"utamp1"``) or a parsed `Domain`;
    `search` one of `SEARCH_CONFIGS`; `timeout` the default limit (s) of one `plan` call.
    At most `max_keys` keys and `max_tasks_per_key` tasks per key are kept.
    """

    def __init__(
        self,
        domain: str | Domain = "utamp2",
        *,
        search: str = DEFAULT_SEARCH,
        timeout: float = 30.0,
        object_type: str = "obj",
        max_keys: int = 32,
        max_tasks_per_key: int = 4,
    ) -> None:
        with paused_gc():  # the decoded domain and the grounder's joins: one pause, not two
            if isinstance(domain, str):
                domain = cached_domain(domain_text(domain), f"{domain}.pddl")
            if search not in SEARCH_CONFIGS:
                raise UnknownNameError("search configuration", search, SEARCH_CONFIGS)
            if max_keys < 1 or max_tasks_per_key < 1:
                raise ValueError("max_keys and max_tasks_per_key must be at least 1")
            self.domain, self.search = domain, search
            self.timeout = check_timeout(timeout)
            self.object_type = object_type
            self._fluent = domain.fluent_predicates()
            self._grounder = Grounder(domain)
        self._cache: OrderedDict[tuple[object, ...], _KeyTasks] = OrderedDict()
        self._max_keys, self._max_tasks = max_keys, max_tasks_per_key
        self._hits = self._groundings = self._uncovered = 0

    def cache_info(self) -> CacheInfo:
        tasks = sum(len(k.tasks) for k in self._cache.values())
        return CacheInfo(self._hits, self._groundings, self._uncovered, tasks)

    def clear(self) -> None:
        """Drop every cached task (the join orders are kept)."""
        self._cache.clear()

    def plan(
        self,
        objects: Mapping[str, str] | Iterable[str],
        static_atoms: Iterable[str],
        fluent_atoms: Iterable[str],
        goal_atoms: Iterable[str],
        *,
        exclude: Collection[str] = frozenset(),
        deadline: Deadline | None = None,
        source: str = "state",
    ) -> PlanResult:
        """Plan from the state `fluent_atoms` (with `static_atoms`) to `goal_atoms`.

        Atoms are PDDL strings such as ``"(oc on slot1 tray)"`` (goal atoms may be negated,
        ``"(not ...)"``); `objects` maps object names to types, or lists names of type
        `object_type` (domain constants are implicit). No step of the plan is one of the
        ground actions in `exclude` (``"(pick-support ...)"``). The limit is `deadline`, else
        the planner's `timeout` from now. Raises ValueError for a malformed atom or one on the
        wrong side (a static predicate among the fluent atoms or vice versa), `PddlError` for
        unknown predicates or objects and `PlanningTimeout` (with its phase) on time-out.
        """
        start = time.perf_counter()
        deadline = deadline if deadline is not None else Deadline.after(self.timeout, start)
        objs = (
            dict(objects)
            if isinstance(objects, Mapping)
            else dict.fromkeys(objects, self.object_type)
        )
        with paused_gc() as resume:
            key = (frozenset(objs.items()), frozenset(static_atoms), tuple(goal_atoms))
            state = frozenset(self._atoms(fluent_atoms, fluent=True))
            task, found = self._task(key, objs, state, deadline, source)
            if not task.solvable:
                elapsed = time.perf_counter() - start
                return PlanResult(False, (), None, elapsed, elapsed, 0.0, UNREACHABLE, None)
            drop = {task.op_index[n] for n in map(action_name, exclude) if n in task.op_index}
            text = task.text(state, drop)
            deadline.check("sas")
            # the collection the grounding's objects set off runs while the search does
            result = search_sas(
                text, search=self.search, deadline=deadline, start=start, started=resume
            )
        if result.solved and len(result.plan) > 1 and self.search in SATISFICING_SEARCHES:
            ops = {op.name: op for op in task.ops}
            plan = eliminate(result.plan, ops, state | found.static, found.goal)
            result = result._replace(
                plan=plan, cost=len(plan), planning_time_s=time.perf_counter() - start
            )
        return result

    # ------------------------------------------------------------------ internals
    def _task(
        self,
        key: tuple[frozenset[tuple[str, str]], frozenset[str], tuple[str, ...]],
        objects: dict[str, str],
        state: frozenset[Atom],
        deadline: Deadline,
        source: str,
    ) -> tuple[SasTask, _KeyTasks]:
        """A cached task of `key` that covers `state`, else a new grounding (then cached)."""
        found = self._cache.get(key)
        if found is not None:
            self._cache.move_to_end(key)
            for i, (task, fixed) in enumerate(found.tasks):
                if task.covers(state, fixed) is None:
                    found.tasks.insert(0, found.tasks.pop(i))  # most recently used first
                    self._hits += 1
                    return task, found
            self._uncovered += 1
        else:
            found = _KeyTasks(
                frozenset(self._atoms(key[1], fluent=False)),
                tuple(parse_literal(g) for g in key[2]),
            )
        init = found.static | state
        problem = Problem(
            source, self.domain.name, MappingProxyType(objects), init, found.goal, source
        )
        ops, _ = self._grounder.ground(problem, deadline)
        task = build_sas(ops, init, found.goal, deadline)
        found.tasks.insert(0, (task, frozenset(a for a in state if a not in task.changing)))
        del found.tasks[self._max_tasks :]
        self._cache[key] = found
        self._cache.move_to_end(key)
        while len(self._cache) > self._max_keys:
            self._cache.popitem(last=False)
        self._groundings += 1
        return task, found

    def _atoms(self, texts: Iterable[str], *, fluent: bool) -> list[Atom]:
        out = []
        for text in texts:
            atom = parse_atom(text)
            if atom.predicate not in self.domain.predicates:
                raise PddlError(
                    f"{text}: unknown predicate '{atom.predicate}'; declared: "
                    f"{', '.join(sorted(self.domain.predicates))}"
                )
            if (atom.predicate in self._fluent) != fluent:
                side = "fluent" if fluent else "static"
                raise ValueError(
                    f"{text} is given as a {side} atom, but '{atom.predicate}' is "
                    f"{'static' if fluent else 'fluent'} in domain '{self.domain.name}'"
                )
            out.append(atom)
        return out


def problem_atoms(
    domain: Domain, problem: Problem
) -> tuple[Mapping[str, str], list[str], list[str], list[str]]:
    """A parsed problem as `StatePlanner.plan` arguments: objects, static, fluent, goal."""
    fluent = domain.fluent_predicates()
    static = [str(a) for a in problem.init if a.predicate not in fluent]
    state = [str(a) for a in problem.init if a.predicate in fluent]
    return problem.objects, static, state, [str(lit) for lit in problem.goal]


__all__ = [
    "UNREACHABLE",
    "CacheInfo",
    "StatePlanner",
    "action_name",
    "parse_atom",
    "parse_literal",
    "problem_atoms",
]
