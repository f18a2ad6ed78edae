"""Plan validation under STRIPS semantics, with one-line diagnostics.

A plan is applied step by step: every precondition literal is checked on the current state,
then delete effects are removed and add effects added (so an atom both deleted and added ends
up true); conditional effects count when their (static) condition holds in the state. The
first failure is reported as data (`ValidationResult`), never as an exception, so callers
such as the evaluation harness can count and explain failures. Only malformed *input text*
(`validate_files`) raises `PddlError`.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl import (
    Atom,
    Domain,
    Literal,
    Problem,
    check_problem,
    parse_domain,
    parse_plan,
    parse_problem,
)


@dataclass(frozen=True)
class ValidationResult:
    """Outcome of `validate_plan`; `failing_step` is 1-based, literals are PDDL text.

    `final_state` is the state after the last applied step (static atoms included); it is
    excluded from equality and repr.
    """

    valid: bool
    steps_applied: int
    failing_step: int | None = None
    failing_action: str | None = None
    failed_precondition: str | None = None
    goal_unmet: tuple[str, ...] = ()
    message: str = ""
    final_state: frozenset[Atom] = field(default=frozenset(), compare=False, repr=False)


def holds(literal: Literal, state: frozenset[Atom] | set[Atom]) -> bool:
    """Truth of a ground literal in `state` (closed world; ``=`` compares the two names)."""
    atom = literal.atom
    true = atom.args[0] == atom.args[1] if atom.predicate == "=" else atom in state
    return true == literal.positive


def _step_error(domain: Domain, objects: dict[str, str], step: tuple[str, ...]) -> str | None:
    """Why `step` is not a well-formed ground action of `domain`, or None if it is."""
    if not step:
        return "empty action"
    name, args = step[0], step[1:]
    action = domain.actions.get(name)
    if action is None:
        return f"unknown action '{name}'; valid: {', '.join(sorted(domain.actions))}"
    if len(args) != action.arity:
        sig = " ".join(f"{v} - {t}" for v, t in action.parameters)
        return f"action '{name}' takes {action.arity} argument(s) ({sig}), got {len(args)}"
    for (var, typ), obj in zip(action.parameters, args, strict=True):
        if obj not in objects:
            return f"unknown object '{obj}'"
        if not domain.is_subtype(objects[obj], typ):
            return (
                f"object '{obj}' has type '{objects[obj]}' but parameter {var} of "
                f"'{name}' needs type '{typ}'"
            )
    return None


def validate_plan(
    domain: Domain, problem: Problem, plan: Iterable[Sequence[str]]
) -> ValidationResult:
    """Apply `plan` (steps ``(name, arg, ...)``, as from `parse_plan`) and check the goal.

    Raises `PddlError` only if `problem` does not fit `domain`; every defect of the plan
    itself (unknown action/object, wrong arity or type, false precondition, unmet goal) is an
    invalid result naming the step and the reason.
    """
    check_problem(domain, problem)
    objects = {**domain.constants, **problem.objects}
    state = set(problem.init)
    applied = 0
    for number, raw in enumerate(plan, 1):
        step = tuple(str(x).lower() for x in raw)
        label = "(" + " ".join(step) + ")"
        error = _step_error(domain, objects, step)
        failed = None
        if error is None:
            pre, add, delete = domain.actions[step[0]].instantiate(step[1:], state)
            failed = next((lit for lit in pre if not holds(lit, state)), None)
            if failed is not None:
                error = f"precondition {domain.show(failed)} is false"
        if error is not None:
            return ValidationResult(
                valid=False,
                steps_applied=applied,
                failing_step=number,
                failing_action=label,
                failed_precondition=None if failed is None else domain.show(failed),
                message=f"step {number} {label}: {error}",
                final_state=frozenset(state),
            )
        state.difference_update(delete)
        state.update(add)
        applied += 1
    unmet = tuple(domain.show(lit) for lit in problem.goal if not holds(lit, state))
    if unmet:
        what = (
            f"goal literal {unmet[0]} is false"
            if len(unmet) == 1
            else f"{len(unmet)} goal literals are false: {', '.join(unmet)}"
        )
        message = f"plan applied but {what}"
    else:
        message = f"plan valid: {applied} steps reach the goal"
    return ValidationResult(
        valid=not unmet,
        steps_applied=applied,
        goal_unmet=unmet,
        message=message,
        final_state=frozenset(state),
    )


def _read(path: str | Path, what: str) -> str:
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise PddlError(f"{path}: cannot read {what} file: {exc.strerror or exc}") from exc


def validate_files(
    domain_path: str | Path, problem_path: str | Path, plan_path: str | Path
) -> ValidationResult:
    """Read and parse the three files (errors name the file), then `validate_plan`."""
    domain = parse_domain(_read(domain_path, "domain"), source=str(domain_path))
    problem = parse_problem(_read(problem_path, "problem"), source=str(problem_path), domain=domain)
    plan = parse_plan(_read(plan_path, "plan"), source=str(plan_path))
    return validate_plan(domain, problem, plan)
