"""Exported PDDL in another planning library: unified-planning (the dev extra) parses the
exported domain and problem of every suite and split, and validates our plans there
(`utamp_gym.symbolic.export`)."""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pytest

from utamp_gym.cli import main
from utamp_gym.planning import fast_downward
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.model import Scene
from utamp_gym.suites import ALL_SUITES, resolve_scene, suite_scenes
from utamp_gym.symbolic.export import (
    ExportedTask,
    domain_symbols,
    export_task,
    exported_plan,
    renames_in,
    scene_plan,
)
from utamp_gym.symbolic.pddl import cached_domain, parse_problem
from utamp_gym.symbolic.problem import DOMAINS, build_problem, domain_text

pytest.importorskip("unified_planning", reason="the dev extra (unified-planning) is not installed")

from unified_planning.engines import ValidationResultStatus
from unified_planning.exceptions import UPProblemDefinitionError
from unified_planning.io import PDDLReader
from unified_planning.shortcuts import PlanValidator, get_environment

get_environment().credits_stream = None  # no banner on stdout
# unified-planning 1.3 calls pyparsing's camelCase names, deprecated in pyparsing 3.3
pytestmark = pytest.mark.filterwarnings("ignore:'parseString' deprecated")


def up_validate(task: ExportedTask) -> ValidationResultStatus | None:
    """Parse the exported files with unified-planning; validate the plan if there is one."""
    reader = PDDLReader()
    problem = reader.parse_problem_string(task.domain, task.problem)
    if not task.plan:
        return None
    plan = reader.parse_plan_string(problem, "".join(f"{s}\n" for s in task.plan))
    with PlanValidator(name="sequential_plan_validator") as validator:
        return validator.validate(problem, plan).status


def exported(scene: Scene, method: str = "utamp2-gt") -> tuple[Any, ExportedTask]:
    out = plan_scene(scene, method, timeout=120)
    return out, export_task(out.domain, out.problem, out.plan, scene.name)


def sample(suite: str) -> list[Scene]:
    """The first scene and the middle one."""
    scenes = suite_scenes(suite)
    return [scenes[0], scenes[len(scenes) // 2]]


def objects_of(task: ExportedTask) -> Iterable[str]:
    return parse_problem(task.problem).objects


CLASH = """(define (problem clash)
  (:domain utamp2)
  (:objects base base-obj obj OC pick-support slot1 - obj)
  (:init (base base back) (base obj back) (isObjEqual oc oc) (force pick-support on)
         (oc on slot1 base) ; base stands on slot1
         (oc under base slot1))
  (:goal (and (oc in hand air) (not (oc on slot1 base)))))
"""


def test_colliding_objects_are_renamed_where_they_are_objects_only() -> None:
    task = export_task(domain_text("utamp2"), CLASH)
    assert dict(task.renames) == {
        "base": "base-obj2",  # base-obj is taken by another object
        "obj": "obj-obj",  # a type
        "oc": "oc-obj",  # a predicate (names are case-insensitive)
        "pick-support": "pick-support-obj",  # an action
    }
    assert renames_in(task.problem) == task.renames
    problem = parse_problem(task.problem)
    assert list(problem.objects) == [
        "base-obj2", "base-obj", "obj-obj", "oc-obj", "pick-support-obj", "slot1"
    ]  # fmt: skip
    assert set(problem.objects.values()) == {"obj"}  # the type after '-' is kept
    assert {str(a) for a in problem.init} == {
        "(base base-obj2 back)",
        "(base obj-obj back)",
        "(isobjequal oc-obj oc-obj)",
        "(force pick-support-obj on)",
        "(oc on slot1 base-obj2)",
        "(oc under base-obj2 slot1)",
    }
    assert [str(g) for g in problem.goal] == ["(oc in hand air)", "(not (oc on slot1 base-obj2))"]
    assert "; base stands on slot1" in task.problem  # comments are kept
    steps = ("(pick-support base base-obj on left right back on slot1 under on)",)
    assert exported_plan(steps, task.renames) == (
        "(pick-support base-obj2 base-obj on left right back on slot1 under on)",
    )
    assert scene_plan(exported_plan(steps, task.renames), task.renames) == steps
    with pytest.raises(UPProblemDefinitionError, match="already defined"):
        PDDLReader().parse_problem_string(task.domain, CLASH)
    PDDLReader().parse_problem_string(task.domain, task.problem)


def test_a_problem_without_collisions_is_exported_unchanged() -> None:
    out, task = exported(resolve_scene("pick-place/000"))
    assert task.renames == {} and task.problem == out.problem and task.plan == out.plan


@pytest.mark.parametrize("suite", ALL_SUITES)
def test_unified_planning_parses_exports_and_validates_our_plans(suite: str) -> None:
    validated = 0
    for scene in sample(suite):
        out, task = exported(scene)
        status = up_validate(task)
        assert status in (None, ValidationResultStatus.VALID), scene.name
        validated += status is not None
        assert scene_plan(task.plan, task.renames) == out.plan
        if suite.startswith("procedural"):
            assert dict(task.renames) == {"base": "base-obj"}, scene.name
    assert validated >= 1


@pytest.mark.parametrize("name", ["pick-place/000", "procedural-v1/train/0000"])
def test_unified_planning_validates_utamp1_plans(name: str) -> None:
    out, task = exported(resolve_scene(name), "utamp1")
    assert out.solved and up_validate(task) == ValidationResultStatus.VALID
    broken = task._replace(plan=task.plan[1:])  # the validator does check
    assert up_validate(broken) == ValidationResultStatus.INVALID


def assert_no_object_is_a_symbol(scenes: Iterable[Scene]) -> None:
    """Object names do not depend on the affordances: the problems are built without."""
    for domain in DOMAINS:
        symbols = domain_symbols(cached_domain(domain_text(domain), domain))
        for scene in scenes:
            problem = build_problem(scene, (), domain)
            task = export_task(domain_text(domain), problem.text, source=scene.name)
            assert not symbols & set(objects_of(task)), (domain, scene.name)
            assert set(task.renames) == symbols & set(problem.objects), (domain, scene.name)


def test_no_exported_object_is_a_domain_symbol() -> None:
    assert_no_object_is_a_symbol(s for suite in ALL_SUITES for s in sample(suite))


@pytest.mark.slow
def test_no_exported_object_of_any_scene_is_a_domain_symbol() -> None:
    assert_no_object_is_a_symbol(s for suite in ALL_SUITES for s in suite_scenes(suite))


def test_fast_downward_plans_the_export_as_the_original() -> None:
    """Renaming does not change Fast Downward's plan (its translator and search)."""
    out, task = exported(resolve_scene("procedural-v1/test-count/0054"))
    assert task.renames and out.solved
    for translator in ("fd", "utamp"):
        before = fast_downward.solve(out.domain, out.problem, translator=translator, timeout=120)
        after = fast_downward.solve(task.domain, task.problem, translator=translator, timeout=120)
        assert len(before.plan) == out.plan_length, translator
        assert scene_plan(after.plan, task.renames) == tuple(before.plan), translator


def test_plan_out_writes_files_unified_planning_accepts(capsys, tmp_path: Path) -> None:
    name = "procedural-v1/test-count/0054"
    assert main(["plan", name, "--json", "--out", str(tmp_path)]) == 0
    printed = tuple(json.loads(capsys.readouterr().out)["plan"])
    files = [tmp_path / f for f in ("domain.pddl", "problem.pddl", "plan.txt")]
    domain, problem, plan = (f.read_text() for f in files)
    assert problem.startswith("; renamed object: base -> base-obj ('base' is a predicate")
    steps = tuple(plan.splitlines())
    assert scene_plan(steps, renames_in(problem)) == printed and steps != printed
    assert up_validate(ExportedTask(domain, problem, steps, {})) == ValidationResultStatus.VALID
    assert main(["validate", *map(str, files)]) == 0


@pytest.mark.slow
@pytest.mark.parametrize("suite", ALL_SUITES)
def test_unified_planning_on_every_scene(suite: str) -> None:
    """Every U-TAMP-2 plan validates; every U-TAMP-1 problem parses (not planned: slow)."""
    for scene in suite_scenes(suite):
        _, task = exported(scene)
        assert up_validate(task) in (None, ValidationResultStatus.VALID), scene.name
        utamp1 = build_problem(scene, (), "utamp1").text
        assert up_validate(export_task(domain_text("utamp1"), utamp1)) is None, scene.name


@pytest.mark.slow
@pytest.mark.parametrize("split", [s for s in ALL_SUITES if s.startswith("procedural")])
def test_fast_downward_plans_every_export_as_the_original(split: str) -> None:
    """Same verdict, same plan (up to the renaming) with both translators."""
    for scene in suite_scenes(split):
        out, task = exported(scene)
        for translator in ("fd", "utamp"):
            before = fast_downward.solve(out.domain, out.problem, translator=translator)
            after = fast_downward.solve(task.domain, task.problem, translator=translator)
            where = (scene.name, translator)
            assert before.solved == after.solved == out.solved, where
            assert len(before.plan) == out.plan_length, where
            assert scene_plan(after.plan, task.renames) == tuple(before.plan), where
