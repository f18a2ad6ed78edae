"""slide-support's conditional effect through the whole toolchain (sliding/000).

Sliding the tray into reach brings every member of the tray into the workspace:
``(forall (?m - obj) (when (isMember ?obj1 ?m) (oc in workspace ?m)))``. The validator, our
grounder + SAS writer + search, Fast Downward's own translator, its driver and the env's
action universe must all give the four member atoms after the first step of sliding/000.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import pytest

from utamp_gym.cli import main
from utamp_gym.planning import fast_downward as fd
from utamp_gym.planning.methods import plan_scene
from utamp_gym.suites import resolve_scene
from utamp_gym.symbolic.pddl import parse_domain, parse_plan, parse_problem
from utamp_gym.symbolic.validate import validate_plan

MEMBERS = tuple(
    f"(oc in workspace tray-{m})" for m in ("body", "handle-front", "edge-left", "edge-right")
)
FORALL = "(forall (?m - obj) (when (isMember ?obj1 ?m) (oc in workspace ?m)))"


@pytest.fixture(scope="module")
def sliding000() -> tuple[str, str, str]:
    """(domain, problem whose goal is the four member atoms, the slide step) of sliding/000."""
    out = plan_scene(resolve_scene("sliding/000"), "utamp2-gt")
    assert out.solved and out.plan[0].startswith("(slide-support tray ")
    problem = out.problem[: out.problem.index("(:goal")]
    problem += "(:goal (and " + " ".join(MEMBERS) + ")))\n"
    return out.domain, problem, out.plan[0]


def test_the_packaged_domain_has_the_forall(sliding000: tuple[str, str, str]) -> None:
    assert FORALL in sliding000[0]


def test_validator_adds_the_member_atoms(sliding000: tuple[str, str, str]) -> None:
    domain_text, problem_text, slide = sliding000
    domain = parse_domain(domain_text)
    problem = parse_problem(problem_text, domain=domain)
    assert not {str(a) for a in problem.init} & set(MEMBERS)
    result = validate_plan(domain, problem, parse_plan(slide))
    assert result.valid, result.message
    assert set(MEMBERS) <= {str(a) for a in result.final_state}
    without = parse_domain(domain_text.replace(FORALL, ""))
    assert validate_plan(without, problem, parse_plan(slide)).goal_unmet  # the test can fail


def test_utamp_validate_accepts_the_one_step_plan(
    sliding000: tuple[str, str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    files = [tmp_path / n for n in ("domain.pddl", "problem.pddl", "plan.txt")]
    for path, text in zip(files, (*sliding000[:2], sliding000[2] + "\n"), strict=True):
        path.write_text(text)
    assert main(["validate", *map(str, files)]) == 0
    assert "valid: 1 steps reach the goal" in capsys.readouterr().out


@pytest.mark.parametrize("translator", fd.TRANSLATORS)
def test_both_translators_plan_the_slide_for_the_member_goal(
    sliding000: tuple[str, str, str], translator: str
) -> None:
    domain, problem, slide = sliding000
    result = fd.solve(domain, problem, translator=translator)
    assert result.solved and result.plan == (slide,), (translator, result)
    unreachable = fd.solve(domain.replace(FORALL, ""), problem, translator=translator)
    assert not unreachable.solved and "unsolvable" in (unreachable.reason or "")


def test_driver_plans_the_slide_for_the_member_goal(
    sliding000: tuple[str, str, str], tmp_path: Path
) -> None:
    (tmp_path / "d.pddl").write_text(sliding000[0])
    (tmp_path / "p.pddl").write_text(sliding000[1])
    result = fd.solve_with_driver(tmp_path / "d.pddl", tmp_path / "p.pddl")
    assert result.solved and result.plan == (sliding000[2],)


def test_our_sas_writes_the_member_effects(sliding000: tuple[str, str, str]) -> None:
    from utamp_gym.planning.sas import to_sas
    from utamp_gym.symbolic.reach import reachable_ops

    domain, problem = parse_domain(sliding000[0]), parse_problem(sliding000[1])
    ops, reached, _ = reachable_ops(domain, problem)
    slide = next(op for op in ops if f"({op.name})" == sliding000[2])
    assert set(MEMBERS) <= {str(a) for a in slide.add}
    assert set(MEMBERS) <= {str(a) for a in reached}
    sas = to_sas(ops, problem.init, problem.goal)
    assert sas is not None
    block = sas[sas.index(f"begin_operator\n{sliding000[2][1:-1]}\n") :]
    block = block[: block.index("end_operator")]
    for atom in MEMBERS:
        name = "Atom oc(" + ", ".join(atom[1:-1].split()[1:]) + ")"
        var = sas[: sas.index(name + "\n")].count("begin_variable") - 1
        assert f" {var} -1 0\n" in block or f" {var} 1 0\n" in block, atom  # set to true


def test_env_universe_successor_has_the_member_atoms() -> None:
    env = gym.make("UTampKitchenSlide-v0", grounding="symbolic")
    env.reset(seed=0, options={"scene": "sliding/000"})
    kitchen = env.unwrapped
    slide = plan_scene(resolve_scene("sliding/000"), "utamp2-gt").plan[0]
    assert not set(MEMBERS) & set(kitchen.true_atoms())
    _, _, _, _, info = env.step(kitchen.universe.index(slide))
    assert info["failure_reason"] == ""
    assert set(MEMBERS) <= set(kitchen.true_atoms())
