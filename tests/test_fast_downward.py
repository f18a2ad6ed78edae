"""Tests of utamp_gym.planning.fast_downward on a small typed blocksworld.

Plans are checked by applying them with a tiny STRIPS simulator of the same domain,
and optimal lengths are computed by breadth-first search over that simulator.
"""

from __future__ import annotations

import importlib.util
import itertools
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections import deque
from pathlib import Path

import pytest
from procs import downward_children, process_alive, user_env

from utamp_gym.errors import PddlError, PlanningError, PlanningTimeout, UnknownNameError
from utamp_gym.planning import downward, processes
from utamp_gym.planning import fast_downward as fd

DOMAIN = """
(define (domain blocks)
  (:requirements :strips :typing :negative-preconditions :equality)
  (:types block)
  (:predicates (on ?x - block ?y - block) (ontable ?x - block) (clear ?x - block)
               (holding ?x - block) (busy) (glued ?x - block))
  (:action pick-up
    :parameters (?x - block)
    :precondition (and (clear ?x) (ontable ?x) (not (busy)))
    :effect (and (not (ontable ?x)) (not (clear ?x)) (busy) (holding ?x)))
  (:action put-down
    :parameters (?x - block)
    :precondition (holding ?x)
    :effect (and (not (holding ?x)) (clear ?x) (not (busy)) (ontable ?x)))
  (:action stack
    :parameters (?x - block ?y - block)
    :precondition (and (holding ?x) (clear ?y) (not (= ?x ?y)))
    :effect (and (not (holding ?x)) (not (clear ?y)) (clear ?x) (not (busy)) (on ?x ?y)))
  (:action unstack
    :parameters (?x - block ?y - block)
    :precondition (and (on ?x ?y) (clear ?x) (not (busy)))
    :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (busy) (not (on ?x ?y)))))
"""


def problem(towers: list[list[str]], goal: str, name: str = "p") -> str:
    """A problem whose initial state is ``towers`` (each listed bottom to top)."""
    objects = " ".join(b for t in towers for b in t)
    return f"""(define (problem {name}) (:domain blocks)
  (:objects {objects} - block)
  (:init {" ".join(f"({a})" for a in sorted(init_atoms(towers)))})
  (:goal (and {goal})))"""


def init_atoms(towers: list[list[str]]) -> frozenset[str]:
    atoms = set()
    for tower in towers:
        atoms.add(f"ontable {tower[0]}")
        atoms.update(f"on {top} {below}" for below, top in itertools.pairwise(tower))
        atoms.add(f"clear {tower[-1]}")
    return frozenset(atoms)


SUSSMAN = [["a", "c"], ["b"]]  # c on a; goal: a on b on c (optimal length 6)
SUSSMAN_GOAL = {"on a b", "on b c"}
SUSSMAN_PROBLEM = problem(SUSSMAN, "(on a b) (on b c)", "sussman")


def successors(state: frozenset[str], blocks: list[str]):
    """Yield (action, next state) of the test domain, mirroring the PDDL above."""

    def step(delete: set[str], add: set[str]) -> frozenset[str]:
        return state - delete | add

    busy = "busy" in state
    for x in blocks:
        if not busy and f"clear {x}" in state and f"ontable {x}" in state:
            yield f"(pick-up {x})", step({f"ontable {x}", f"clear {x}"}, {"busy", f"holding {x}"})
        if f"holding {x}" in state:
            yield f"(put-down {x})", step({f"holding {x}", "busy"}, {f"clear {x}", f"ontable {x}"})
        for y in blocks:
            if x == y:
                continue
            if f"holding {x}" in state and f"clear {y}" in state:
                yield (
                    f"(stack {x} {y})",
                    step({f"holding {x}", f"clear {y}", "busy"}, {f"clear {x}", f"on {x} {y}"}),
                )
            if not busy and f"on {x} {y}" in state and f"clear {x}" in state:
                yield (
                    f"(unstack {x} {y})",
                    step({f"clear {x}", f"on {x} {y}"}, {"busy", f"holding {x}", f"clear {y}"}),
                )


def simulate(plan: tuple[str, ...], towers: list[list[str]]) -> frozenset[str]:
    """Apply ``plan`` from the initial state; fail if an action is not applicable."""
    blocks = [b for t in towers for b in t]
    state = init_atoms(towers)
    for step in plan:
        moves = dict(successors(state, blocks))
        assert step in moves, f"inapplicable action {step} in {sorted(state)}"
        state = moves[step]
    return state


def optimal_length(towers: list[list[str]], goal: set[str]) -> int:
    blocks = [b for t in towers for b in t]
    start = init_atoms(towers)
    frontier, seen = deque([(start, 0)]), {start}
    while frontier:
        state, depth = frontier.popleft()
        if goal <= state:
            return depth
        for _, nxt in successors(state, blocks):
            if nxt not in seen:
                seen.add(nxt)
                frontier.append((nxt, depth + 1))
    raise AssertionError("goal unreachable")


@pytest.mark.parametrize("search", fd.SEARCH_CONFIGS)
def test_plan_reaches_goal(search):
    result = fd.solve(DOMAIN, SUSSMAN_PROBLEM, search=search)
    assert result.solved and result.reason is None
    assert simulate(result.plan, SUSSMAN) >= SUSSMAN_GOAL
    assert len(result.plan) == result.cost >= 6  # unit costs; 6 is optimal
    assert all(step == step.lower() and step.startswith("(") for step in result.plan)
    assert result.expanded is not None and result.expanded >= 0
    assert result.planning_time_s >= result.translate_time_s > 0
    assert result.search_time_s > 0


def test_astar_lmcut_is_optimal():
    towers = [["d", "c", "b", "a"]]  # a on b on c on d; goal: the reversed tower
    goal = {"on d c", "on c b", "on b a"}
    text = problem(towers, " ".join(f"({g})" for g in sorted(goal)))
    result = fd.solve(DOMAIN, text, search="astar-lmcut")
    assert result.solved
    assert simulate(result.plan, towers) >= goal
    assert len(result.plan) == result.cost == optimal_length(towers, goal)
    assert fd.solve(DOMAIN, SUSSMAN_PROBLEM, search="astar-lmcut").cost == 6


@pytest.mark.parametrize("search", fd.SEARCH_CONFIGS)
def test_search_proves_unsolvable(search):
    cyclic = problem(SUSSMAN, "(on a b) (on b a)")
    result = fd.solve(DOMAIN, cyclic, search=search)
    assert not result.solved
    assert result.plan == () and result.cost is None
    assert result.reason == "search space exhausted: task unsolvable"


@pytest.mark.parametrize("translator", fd.TRANSLATORS)
def test_translator_proves_unsolvable(translator):
    result = fd.solve(DOMAIN, problem(SUSSMAN, "(on a b) (glued c)"), translator=translator)
    assert not result.solved and result.plan == ()
    assert "proved unsolvable by" in result.reason


def test_empty_goal_gives_empty_plan():
    result = fd.solve(DOMAIN, problem(SUSSMAN, "(on c a)"))
    assert result.solved and result.plan == () and result.cost == 0


def test_driver_gives_valid_plan(tmp_path):
    (tmp_path / "domain.pddl").write_text(DOMAIN)
    (tmp_path / "problem.pddl").write_text(SUSSMAN_PROBLEM)
    (tmp_path / "cyclic.pddl").write_text(problem(SUSSMAN, "(on a b) (on b a)"))
    result = fd.solve_with_driver(tmp_path / "domain.pddl", tmp_path / "problem.pddl")
    assert result.solved
    assert simulate(result.plan, SUSSMAN) >= SUSSMAN_GOAL
    assert len(result.plan) == result.cost
    assert result.plan == fd.solve(DOMAIN, SUSSMAN_PROBLEM).plan  # same deterministic search
    unsolvable = fd.solve_with_driver(tmp_path / "domain.pddl", tmp_path / "cyclic.pddl")
    assert not unsolvable.solved and "unsolvable" in unsolvable.reason


def test_lama_first_matches_installed_driver_alias():
    root = Path(next(iter(importlib.util.find_spec("up_fast_downward").submodule_search_locations)))
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]); from driver.aliases import ALIASES; "
        "print(repr([a.replace(' ', '').replace('\\n', '') for a in ALIASES['lama-first']]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(root / "downward")],
        env=user_env(),
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert out.strip() == repr(list(downward.SEARCH_ARGS["lama-first"]))


def test_unknown_search_name():
    with pytest.raises(UnknownNameError) as info:
        fd.solve(DOMAIN, SUSSMAN_PROBLEM, search="gbfs-magic")
    message = str(info.value)
    assert "gbfs-magic" in message
    assert all(name in message for name in fd.SEARCH_CONFIGS)
    assert isinstance(info.value, KeyError)


@pytest.mark.parametrize(
    ("domain", "prob"),
    [
        (DOMAIN, "(define (problem broken"),
        (DOMAIN, problem(SUSSMAN, "(on a zz)")),
        (
            DOMAIN.replace("(:predicates", "(:functions (f ?x - block) - block) (:predicates"),
            SUSSMAN_PROBLEM,
        ),  # object fluents: the translator calls SystemExit
    ],
)
@pytest.mark.parametrize("translator", fd.TRANSLATORS)
def test_bad_pddl_raises_pddl_error(domain, prob, translator):
    with pytest.raises(PddlError):
        fd.solve(domain, prob, translator=translator)
    assert fd.solve(DOMAIN, SUSSMAN_PROBLEM).solved  # translator state intact afterwards


# 12 blocks in three towers, goal one tower in a scrambled order: seconds even for lmcut.
BIG_PROBLEM = problem(
    [[f"b{i}" for i in range(start, 12, 3)] for start in range(3)],
    " ".join(f"(on b{i * 5 % 12} b{(i * 5 + 5) % 12})" for i in range(11)),
    "big",
)


def test_timeout_kills_search_process():
    """The limit must run out while the search runs: grounding the 12 blocks takes less than
    0.3 s idle (but under two busy processes a 0.3 s limit ran out during grounding, before
    there was a search to kill), blind search takes minutes."""
    with pytest.raises(PlanningTimeout) as info:
        fd.solve(DOMAIN, BIG_PROBLEM, search="astar-blind", timeout=3.0)
    message = str(info.value)
    assert "3 s" in message and "killed" in message
    pid = int(re.search(r"pid (\d+)", message).group(1))
    assert not process_alive(pid)
    assert downward_children() == []


def test_timeout_kills_driver_process_group(tmp_path):
    (tmp_path / "domain.pddl").write_text(DOMAIN)
    (tmp_path / "big.pddl").write_text(BIG_PROBLEM)
    with pytest.raises(PlanningTimeout) as info:
        fd.solve_with_driver(
            tmp_path / "domain.pddl", tmp_path / "big.pddl", alias="seq-opt-lmcut", timeout=0.5
        )
    pgid = int(re.search(r"pid (\d+)", str(info.value)).group(1))
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            assert not (int(fields[2]) == pgid and fields[0] != "Z"), "driver group survived"


def live_children() -> set[int]:
    """Pids of this process's live (non-zombie) children, of any command."""
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == os.getpid() and fields[0] != "Z":
                found.add(int(entry.name))
    return found


@pytest.fixture
def ctrl_c():
    """Python's own SIGINT handler for the test. Python leaves SIGINT ignored if it started
    ignored (a background job of a non-interactive shell, as under `nohup make test &`)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_interrupt_kills_search_process(ctrl_c):
    """A real Ctrl-C (SIGINT to this process) once the search binary runs. It is sent when
    the search is seen, not after a fixed delay: on a machine loaded to 15-19 a delay of
    0.5 s could fall anywhere between grounding and search. The limit is far off, so a lost
    interrupt fails as a time-out."""
    sent: list[float] = []
    started = threading.Event()

    def interrupt_once_searching() -> None:
        limit = time.monotonic() + 60
        while not downward_children() and time.monotonic() < limit and not started.is_set():
            time.sleep(0.005)
        if downward_children():
            sent.append(time.monotonic())
            os.kill(os.getpid(), signal.SIGINT)

    watcher = threading.Thread(target=interrupt_once_searching, daemon=True)
    watcher.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            fd.solve(DOMAIN, BIG_PROBLEM, search="astar-blind", timeout=120)
            started.set()  # only if it returned
    finally:
        started.set()
        watcher.join()
    assert sent, "the search never started"
    assert time.monotonic() - sent[0] < 20  # the interrupt, not the time limit, ended it
    assert downward_children() == []


class _InterruptedStart(subprocess.Popen):
    """A `Popen` hit by Ctrl-C just after it forked, before it returns to its caller."""

    def _execute_child(self, *args, **kwargs):
        super()._execute_child(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGINT)


def test_interrupt_while_a_planner_process_starts_kills_it(ctrl_c, monkeypatch, tmp_path):
    """Raised inside `Popen`, the KeyboardInterrupt used to leave the child unkilled (its pid
    went with the exception): the driver searched on for minutes."""
    (tmp_path / "domain.pddl").write_text(DOMAIN)
    (tmp_path / "big.pddl").write_text(BIG_PROBLEM)
    before = live_children()
    monkeypatch.setattr(processes.subprocess, "Popen", _InterruptedStart)
    with pytest.raises(KeyboardInterrupt):
        fd.solve_with_driver(tmp_path / "domain.pddl", tmp_path / "big.pddl", timeout=60)
    with pytest.raises(KeyboardInterrupt):
        fd.solve(DOMAIN, BIG_PROBLEM, search="astar-blind", timeout=60)
    assert live_children() <= before
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_interrupt_handled_by_another_thread_ends_the_wait(ctrl_c):
    """A SIGINT may be taken by any thread that does not block it (the main thread blocks
    every signal while `subprocess` forks); its Python handler then runs in the main thread
    only when that thread next runs Python code, which the wait on a silent planner process
    used to postpone to the process's end or the time limit."""
    threading.Timer(0.3, lambda: signal.pthread_kill(threading.get_ident(), signal.SIGINT)).start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        processes.run(["sleep", "40"], stdin=None, timeout=40, what="sleep", limit=40)
    assert time.monotonic() - start < 20
    assert not any(
        Path(f"/proc/{pid}/cmdline").read_bytes().startswith(b"sleep") for pid in live_children()
    )


def test_tiny_budget_is_used_up_by_translation():
    with pytest.raises(PlanningTimeout, match="time limit"):
        fd.solve(DOMAIN, BIG_PROBLEM, timeout=1e-6)


def test_repeated_in_process_solves_are_reentrant():
    from fast_downward.translate import options

    before = options.options
    cyclic = problem(SUSSMAN, "(on a b) (on b a)")
    for i in range(50):
        if i % 10 == 9:
            result = fd.solve(DOMAIN, cyclic)
            assert not result.solved and "unsolvable" in result.reason
            continue
        result = fd.solve(DOMAIN, SUSSMAN_PROBLEM, search=fd.SEARCH_CONFIGS[i % 3])
        assert result.solved
        assert simulate(result.plan, SUSSMAN) >= SUSSMAN_GOAL
    assert options.options is before
    assert downward_children() == []


def test_missing_planner_raises_planning_error(monkeypatch):
    fd.downward_paths.cache_clear()
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None)
    try:
        with pytest.raises(PlanningError, match="up-fast-downward"):
            fd.solve(DOMAIN, SUSSMAN_PROBLEM)
    finally:
        monkeypatch.undo()
        fd.downward_paths.cache_clear()
    assert fd.solve(DOMAIN, SUSSMAN_PROBLEM).solved
