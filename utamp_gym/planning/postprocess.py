"""Greedy action elimination: drop actions a satisficing plan does not need.

lama-first is greedy and sometimes moves an object aside and back. For each action in
turn, remove it and every later action that then becomes inapplicable; if the goal
still holds, keep the shorter plan (Nakhost and Müller's greedy action elimination).
The result is a valid plan never longer than the input.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from utamp_gym.symbolic.pddl import Atom, Literal
from utamp_gym.symbolic.reach import GroundOp


def _run(
    plan: Sequence[GroundOp], init: frozenset[Atom], skip: int
) -> tuple[list[GroundOp], frozenset[Atom]]:
    state, kept = set(init), []
    for i, op in enumerate(plan):
        if i == skip:
            continue
        if all(a in state for a in op.pre) and not any(a in state for a in op.pre_neg):
            state.difference_update(op.delete)
            state.update(op.add)
            kept.append(op)
    return kept, frozenset(state)


def _goal(state: frozenset[Atom], goal: Sequence[Literal]) -> bool:
    return all((lit.atom in state) == lit.positive for lit in goal)


def eliminate(
    plan: Sequence[str], ops: Mapping[str, GroundOp], init: frozenset[Atom], goal: Sequence[Literal]
) -> tuple[str, ...]:
    """The plan (PDDL strings) with redundant actions removed."""
    current = [ops[step.strip("()")] for step in plan]
    i = 0
    while i < len(current):
        shorter, state = _run(current, init, i)
        if _goal(state, goal):
            current = shorter  # retry the same index: the next action moved into it
        else:
            i += 1
    return tuple(f"({op.name})" for op in current)
