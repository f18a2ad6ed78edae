"""Grounding tests: structure, semantics, and agreement with the validator on random rollouts."""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.errors import PddlError, UnknownNameError
from utamp_gym.symbolic.grounding import Cursor, GroundTask, ground
from utamp_gym.symbolic.pddl import Domain, Problem, parse_domain, parse_problem
from utamp_gym.symbolic.validate import validate_plan

DOMAIN = """\
(define (domain BW)
  (:requirements :strips :typing :negative-preconditions :equality)
  (:types block slot - surface robot)
  (:constants arm - robot)
  (:predicates (on ?b - block ?s - surface) (clear ?s - surface)
               (holding ?r - robot ?b - block) (busy ?r - robot)
               (fitsOn ?b - block ?s - surface))
  (:action pick
    :parameters (?b - block ?s - surface)
    :precondition (and (not (= ?b ?s)) (on ?b ?s) (clear ?b) (not (busy arm)))
    :effect (and (holding arm ?b) (busy arm) (clear ?s) (not (on ?b ?s)) (not (clear ?b))))
  (:action place
    :parameters (?b - block ?s - surface)
    :precondition (and (holding arm ?b) (clear ?s) (fitsOn ?b ?s) (not (= ?b ?s)))
    :effect (and (on ?b ?s) (clear ?b) (not (clear ?s)) (not (holding arm ?b))
                 (not (busy arm))))
  (:action regrip
    :parameters (?b - block)
    :precondition (holding arm ?b)
    :effect (and (not (holding arm ?b)) (holding arm ?b))))
"""


def blocks_problem(n: int, slots: int) -> str:
    """n blocks on `slots` slots (extra blocks stacked); a block fits on any later block."""
    blocks = [f"b{i}" for i in range(n)]
    names = [f"s{i}" for i in range(slots)]
    init = [f"(on {b} {names[i]})" if i < slots else f"(on {b} {blocks[i - slots]})"
            for i, b in enumerate(blocks)]
    covered = {blocks[i - slots] for i in range(slots, n)}
    init += [f"(clear {b})" for b in blocks if b not in covered]
    init += [f"(fitsOn {a} {b})" for i, a in enumerate(blocks) for b in blocks[i + 1:]]
    init += [f"(fitsOn {b} {s})" for b in blocks for s in names]
    goal = [f"(on {blocks[i]} {blocks[i + 1]})" for i in range(n - 1)]
    return (f"(define (problem p) (:domain bw) (:objects {' '.join(blocks)} - block "
            f"{' '.join(names)} - slot) (:init {' '.join(init)}) "
            f"(:goal (and {' '.join(goal)} (not (busy arm)))))")


@pytest.fixture
def bw() -> tuple[Domain, Problem, GroundTask]:
    domain = parse_domain(DOMAIN)
    problem = parse_problem(blocks_problem(3, 3), domain=domain)
    return domain, problem, ground(domain, problem)


def test_structure(bw: tuple[Domain, Problem, GroundTask]) -> None:
    _, _, task = bw
    assert list(task.atoms) == sorted(task.atoms) and list(task.actions) == sorted(task.actions)
    assert not any("fitson" in a for a in task.atoms)  # static predicate dropped
    assert "(busy arm)" in task.atoms and "(holding arm b0)" in task.atoms
    assert "(place b0 b0)" not in task.actions  # not (= ?b ?s)
    assert "(place b2 b0)" not in task.actions  # static fitsOn
    assert "(place b0 b2)" in task.actions and "(regrip b1)" in task.actions
    assert not any(a.startswith(("(pick s", "(pick arm")) for a in task.actions)  # types
    assert set(task.true_atoms(task.init)) == {
        "(on b0 s0)", "(on b1 s1)", "(on b2 s2)", "(clear b0)", "(clear b1)", "(clear b2)"}
    assert task.goal_possible and not task.is_goal(task.init)
    assert len(task.actions) == 3 * 5 + 3 + 3 * 3 + 3  # pick, place on blocks/slots, regrip


def test_index_of_and_failed_preconditions(bw: tuple[Domain, Problem, GroundTask]) -> None:
    _, _, task = bw
    i = task.index_of("(PICK b0 s0)")
    assert task.actions[i] == "(pick b0 s0)" == task.actions[task.index_of(("pick", "b0", "s0"))]
    with pytest.raises(UnknownNameError, match="unknown ground action '\\(pick b0 b0\\)'"):
        task.index_of("(pick b0 b0)")
    s = task.apply(task.init, i)
    j = task.index_of("(pick b1 s1)")
    assert not task.is_applicable(s, j) and task.failed_preconditions(s, j) == ["(not (busy arm))"]
    k = task.index_of("(place b0 s0)")
    assert task.is_applicable(s, k) and task.failed_preconditions(s, k) == []
    assert task.failed_preconditions(task.init, k) == ["(clear s0)", "(holding arm b0)"]


def test_apply_does_not_mutate_and_add_wins(bw: tuple[Domain, Problem, GroundTask]) -> None:
    _, _, task = bw
    init = task.init.copy()
    s = task.apply(task.init, task.index_of("(pick b0 s0)"))
    assert (task.init == init).all() and not task.init.flags.writeable
    s2 = task.apply(s, task.index_of("(regrip b0)"))
    assert s2[task.atoms.index("(holding arm b0)")] and (s2 == s).all()


def test_plan_reaches_goal(bw: tuple[Domain, Problem, GroundTask]) -> None:
    _, _, task = bw
    s = task.init
    for step in ["(pick b1 s1)", "(place b1 b2)", "(pick b0 s0)", "(place b0 b1)"]:
        i = task.index_of(step)
        assert task.applicable(s)[i]
        s = task.apply(s, i)
    assert task.is_goal(s)


def test_pack_round_trip_and_bit_matrices(bw: tuple[Domain, Problem, GroundTask]) -> None:
    _, _, task = bw
    s = task.apply(task.init, task.index_of("(pick b0 s0)"))
    words = task.pack(s)
    assert words.dtype == np.uint64 and (task.unpack(words) == s).all()
    bits = task.bit_matrices()
    for kind, (ptr, ids) in task.csr.items():
        for i in range(len(task.actions)):
            row = np.zeros(len(task.atoms), bool)
            row[ids[ptr[i]:ptr[i + 1]]] = True
            assert (bits[kind][i] == task.pack(row)).all()


def test_static_goal_literal_false_makes_goal_impossible() -> None:
    domain = parse_domain(DOMAIN)
    text = blocks_problem(2, 2).replace("(:goal (and", "(:goal (and (fitsOn b1 b0)")
    task = ground(domain, parse_problem(text, domain=domain))
    assert not task.goal_possible and not task.is_goal(task.init)


def test_relevant_only_keeps_reachable_actions() -> None:
    domain = parse_domain(DOMAIN)
    text = blocks_problem(3, 3).replace("(on b2 s2)", "(on b2 b1)").replace("(clear b1)", "")
    problem = parse_problem(text.replace("(clear b2)", "(clear b2) (clear s2)"), domain=domain)
    full, small = ground(domain, problem), ground(domain, problem, relevant_only=True)
    assert set(small.actions) < set(full.actions)
    assert "(pick b1 s1)" in small.actions  # needs (clear b1): reachable by moving b2
    rng = np.random.default_rng(0)
    for _ in range(20):  # every action applicable along a rollout is a relevant one
        s = full.init
        for _ in range(15):
            applicable = np.flatnonzero(full.applicable(s))
            assert {full.actions[i] for i in applicable} <= set(small.actions)
            s = full.apply(s, int(rng.choice(applicable)))


def rollout_agrees_with_validator(domain: Domain, problem: Problem, task: GroundTask,
                                  seed: int, length: int = 20) -> None:
    """A random applicable sequence: grounded state, mask and goal match the validator's."""
    rng = np.random.default_rng(seed)
    fluent = domain.fluent_predicates()
    cursor = task.cursor()
    state, plan = task.init, []
    for _ in range(length):
        mask = task.applicable(state)
        assert (mask == cursor.mask).all()
        for i in rng.choice(len(task.actions), 4, replace=False):  # probe single steps
            probe = validate_plan(domain, problem, [*plan, task.actions[i][1:-1].split()])
            assert (probe.steps_applied > len(plan)) == mask[i] == task.is_applicable(state, i)
        i = int(rng.choice(np.flatnonzero(mask)))
        plan.append(task.actions[i][1:-1].split())
        state = task.apply(state, i)
        cursor.step(i)
        result = validate_plan(domain, problem, plan)
        assert result.steps_applied == len(plan)
        fluent_state = {str(a) for a in result.final_state if a.predicate in fluent}
        assert set(task.true_atoms(state)) == fluent_state
        assert (cursor.state == state).all()
        assert task.is_goal(state) == cursor.is_goal() == result.valid


@pytest.mark.parametrize("incremental", [False, True])
@pytest.mark.parametrize(("n", "slots"), [(3, 3), (5, 2)])
def test_random_rollouts_agree_with_validator(
    n: int, slots: int, incremental: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if incremental:  # force the incremental mask (and hub atoms) on this small task
        monkeypatch.setattr(Cursor, "INCREMENTAL_ABOVE", 0)
        monkeypatch.setattr(Cursor, "HUB_MIN_USERS", 2)
    domain = parse_domain(DOMAIN)
    problem = parse_problem(blocks_problem(n, slots), domain=domain)
    task = ground(domain, problem)
    assert task.cursor().incremental == incremental
    for seed in range(8):
        rollout_agrees_with_validator(domain, problem, task, seed)


def test_cursor_rejects_inapplicable_action(bw: tuple[Domain, Problem, GroundTask]) -> None:
    _, _, task = bw
    cursor = task.cursor()
    with pytest.raises(PddlError, match=r"\(place b0 s1\) is not applicable: "
                       r"\(clear s1\), \(holding arm b0\) false"):
        cursor.step(task.index_of("(place b0 s1)"))
    cursor.step(task.index_of("(pick b0 s0)"))
    cursor.reset()
    assert (cursor.state == task.init).all()
    assert not cursor.mask.flags.writeable
