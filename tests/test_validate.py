"""Plan validation tests on the shared typed blocksworld (`tests/blocksworld.py`)."""

from __future__ import annotations

from pathlib import Path

import pytest
from blocksworld import DOMAIN, PROBLEM

from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl import Atom, parse_domain, parse_problem
from utamp_gym.symbolic.validate import ValidationResult, validate_files, validate_plan

PLAN = [("pick", "b", "s2"), ("place", "b", "c"), ("pick", "a", "s1"), ("place", "a", "b")]


def run(plan: list[tuple[str, ...]]) -> ValidationResult:
    domain = parse_domain(DOMAIN)
    return validate_plan(domain, parse_problem(PROBLEM, domain=domain), plan)


def test_valid_plan() -> None:
    result = run(PLAN)
    assert result.valid and result.steps_applied == 4
    assert result.failing_step is None and result.goal_unmet == ()
    assert result.message == "plan valid: 4 steps reach the goal"
    assert Atom("on", ("a", "b")) in result.final_state
    assert Atom("fitson", ("a", "b")) in result.final_state  # static atoms are kept


def test_negated_precondition_failure_names_step_and_literal() -> None:
    result = run([("pick", "b", "s2"), ("pick", "a", "s1")])
    assert not result.valid
    assert (result.steps_applied, result.failing_step) == (1, 2)
    assert result.failing_action == "(pick a s1)"
    assert result.failed_precondition == "(not (busy arm))"
    assert result.message == "step 2 (pick a s1): precondition (not (busy arm)) is false"


def test_static_failure_uses_declared_spelling() -> None:
    result = run([("pick", "c", "s3"), ("place", "c", "a")])
    assert result.failing_step == 2 and result.failed_precondition == "(fitsOn c a)"
    assert "precondition (fitsOn c a) is false" in result.message


def test_equality_failure() -> None:
    result = run([("pick", "a", "a")])
    assert result.failing_step == 1 and result.failed_precondition == "(not (= a a))"


def test_first_false_precondition_in_schema_order() -> None:
    result = run([("pick", "b", "s2"), ("place", "b", "c"), ("pick", "c", "s3")])
    assert result.failing_step == 3 and result.failed_precondition == "(clear c)"


def test_short_plan_reports_unmet_goal() -> None:
    result = run(PLAN[:3])
    assert not result.valid and result.steps_applied == 3 and result.failing_step is None
    assert result.goal_unmet == ("(on a b)", "(not (busy arm))")
    assert result.message == (
        "plan applied but 2 goal literals are false: (on a b), (not (busy arm))"
    )
    assert run(PLAN[:2]).goal_unmet == ("(on a b)", "(clear s1)")
    assert run([]).steps_applied == 0


def test_add_wins_over_delete() -> None:
    result = run([("pick", "a", "s1"), ("regrip", "a")])
    assert result.steps_applied == 2
    assert Atom("holding", ("arm", "a")) in result.final_state


@pytest.mark.parametrize(
    ("step", "message"),
    [
        (("fly", "a", "s1"), "step 2 (fly a s1): unknown action 'fly'; valid: pick, place, regrip"),
        (
            ("pick", "a"),
            "step 2 (pick a): action 'pick' takes 2 argument(s) (?b - block ?s - surface), got 1",
        ),
        (("pick", "z", "s1"), "step 2 (pick z s1): unknown object 'z'"),
        (
            ("pick", "s1", "a"),
            "step 2 (pick s1 a): object 's1' has type 'slot' but parameter "
            "?b of 'pick' needs type 'block'",
        ),
        (("pick", "arm", "a"), "object 'arm' has type 'robot'"),
    ],
)
def test_malformed_step_is_an_invalid_result(step: tuple[str, ...], message: str) -> None:
    result = run([("pick", "b", "s2"), step, ("place", "b", "c")])
    assert not result.valid
    assert (result.steps_applied, result.failing_step) == (1, 2)
    assert result.failing_action == "(" + " ".join(step) + ")"
    assert result.failed_precondition is None
    assert message in result.message


def test_validate_files(tmp_path: Path) -> None:
    (tmp_path / "domain.pddl").write_text(DOMAIN)
    (tmp_path / "problem.pddl").write_text(PROBLEM)
    lines = [f"({' '.join(step)})" for step in PLAN]
    (tmp_path / "sas_plan").write_text("\n".join(lines) + "\n; cost = 4 (unit cost)\n")
    files = [tmp_path / n for n in ("domain.pddl", "problem.pddl", "sas_plan")]
    assert validate_files(*files).valid
    (tmp_path / "problem.pddl").write_text(
        PROBLEM.replace(
            "(and (on a b) (on b c) (clear s1) (clear s2) (not (busy arm)))", "(on b c)"
        )
    )
    (tmp_path / "sas_plan").write_text("; empty plan\n")
    result = validate_files(*files)
    assert result.goal_unmet == ("(on b c)",) and result.steps_applied == 0
    assert result.message == "plan applied but goal literal (on b c) is false"


def test_validate_files_errors_name_the_file(tmp_path: Path) -> None:
    (tmp_path / "domain.pddl").write_text(DOMAIN)
    (tmp_path / "problem.pddl").write_text(PROBLEM.replace("(clear a)", "(clear q)"))
    (tmp_path / "sas_plan").write_text("(pick a s1)\n")
    files = [tmp_path / n for n in ("domain.pddl", "problem.pddl", "sas_plan")]
    with pytest.raises(PddlError, match=r"problem\.pddl:4: unknown object 'q'"):
        validate_files(*files)
    with pytest.raises(PddlError, match=r"missing\.pddl: cannot read domain file"):
        validate_files(tmp_path / "missing.pddl", *files[1:])
    (tmp_path / "problem.pddl").write_text(PROBLEM)
    (tmp_path / "sas_plan").write_text("(pick a s1\n")
    with pytest.raises(PddlError, match=r"sas_plan:1:"):
        validate_files(*files)
