"""StatePlanner: cached groundings, states the cache does not cover, banned actions, limits."""

from __future__ import annotations

import copy
import gc
import traceback

import pytest
import wide

from utamp_gym.deadline import Deadline
from utamp_gym.errors import PddlError, PlanningTimeout
from utamp_gym.planning import fast_downward
from utamp_gym.planning.methods import PlanOutcome, plan_scene
from utamp_gym.planning.sas import build_sas
from utamp_gym.planning.state_planner import StatePlanner, action_name, problem_atoms
from utamp_gym.suites import resolve_scene
from utamp_gym.symbolic.pddl import Atom, Literal, parse_domain, parse_plan, parse_problem
from utamp_gym.symbolic.reach import GroundOp
from utamp_gym.symbolic.validate import validate_plan

SCENE = "pick-place/105"  # five objects


@pytest.fixture(scope="module")
def gt() -> PlanOutcome:
    out = plan_scene(resolve_scene(SCENE), "utamp2-gt")
    assert out.solved and out.plan_length >= 3
    return out


def task_args(out: PlanOutcome, steps: int = 0) -> tuple:
    """(objects, static, fluent, goal) of the state after the first `steps` plan steps."""
    domain, problem = parse_domain(out.domain), parse_problem(out.problem)
    objects, static, _, goal = problem_atoms(domain, problem)
    done = validate_plan(domain, problem, parse_plan("\n".join(out.plan[:steps])))
    fluent = domain.fluent_predicates()
    return objects, static, sorted(str(a) for a in done.final_state if a.predicate in fluent), goal


def valid_from(out: PlanOutcome, state: list[str], plan: tuple[str, ...]) -> bool:
    """Is `plan` valid from `state` (fluent atoms) in the task of `out`?"""
    domain, problem = parse_domain(out.domain), parse_problem(out.problem)
    _, static, _, goal = problem_atoms(domain, problem)
    text = out.problem[: out.problem.index("(:init")] + "(:init " + " ".join([*static, *state])
    text += ")\n  (:goal (and " + " ".join(goal) + ")))\n"
    check = validate_plan(domain, parse_problem(text), parse_plan("\n".join(plan)))
    return check.valid


def test_replans_from_reached_states_hit_the_cache(gt: PlanOutcome) -> None:
    planner = StatePlanner("utamp2")
    first = planner.plan(*task_args(gt))
    assert first.solved and len(first.plan) == gt.plan_length
    for k in range(1, gt.plan_length):
        args = task_args(gt, k)
        result = planner.plan(*args)
        assert result.solved and len(result.plan) == gt.plan_length - k  # still optimal
        assert valid_from(gt, args[2], result.plan)
    info = planner.cache_info()
    assert (info.groundings, info.hits, info.uncovered, info.tasks) == (1, gt.plan_length - 1, 0, 1)


@pytest.mark.parametrize(
    ("change", "why"),
    [
        (lambda s: [*s, "(oc in hand mug)"], "two atoms of the exactly-one group 'in hand'"),
        (lambda s: [a for a in s if a != "(oc in hand air)"], "no atom of 'in hand'"),
        (lambda s: [*s, "(oc front mug tray)"], "an atom the first grounding never reached"),
        (lambda s: [a for a in s if a != "(oc in workspace slot2)"], "a constant changed"),
    ],
)
def test_states_the_cache_does_not_cover_are_grounded_anew(gt: PlanOutcome, change, why) -> None:
    objects, static, state, goal = task_args(gt)
    planner = StatePlanner("utamp2")
    planner.plan(objects, static, state, goal)
    odd = change(state)
    assert odd != state, why
    result = planner.plan(objects, static, odd, goal)
    info = planner.cache_info()
    assert (info.groundings, info.uncovered, info.tasks) == (2, 1, 2), why
    fresh = StatePlanner("utamp2").plan(objects, static, odd, goal)  # the reference
    assert (result.solved, len(result.plan)) == (fresh.solved, len(fresh.plan)), why
    if result.solved:
        assert valid_from(gt, odd, result.plan), why
    planner.plan(objects, static, state, goal)  # the first task is still there
    assert planner.cache_info().groundings == 2


def test_excluded_actions_never_appear_and_need_no_grounding(gt: PlanOutcome) -> None:
    args = task_args(gt)
    planner = StatePlanner("utamp2")
    planner.plan(*args)
    banned = {gt.plan[0], gt.plan[0].upper().replace("(", "( ")}  # any spelling of it
    assert action_name(gt.plan[0].upper()) == gt.plan[0][1:-1]
    result = planner.plan(*args, exclude=banned)
    assert result.solved and gt.plan[0] not in result.plan
    assert len(result.plan) >= gt.plan_length and valid_from(gt, args[2], result.plan)
    assert planner.cache_info().groundings == 1


def test_keys_are_bounded(gt: PlanOutcome) -> None:
    objects, static, state, goal = task_args(gt)
    planner = StatePlanner("utamp2", max_keys=1)
    planner.plan(objects, static, state, goal)
    planner.plan(objects, static, state, goal[:-1])  # another goal: another key
    assert planner.cache_info().tasks == 1
    planner.plan(objects, static, state, goal)
    assert planner.cache_info().groundings == 3


def test_bad_atoms_raise_clear_errors(gt: PlanOutcome) -> None:
    objects, static, state, goal = task_args(gt)
    planner = StatePlanner("utamp2")
    with pytest.raises(ValueError, match="expected a ground atom"):
        planner.plan(objects, static, [*state, "oc in hand air"], goal)
    with pytest.raises(ValueError, match="'ismember' is static"):
        planner.plan(objects, static, [*state, "(ismember tray tray-body)"], goal)
    with pytest.raises(ValueError, match="'oc' is fluent"):
        planner.plan(objects, [*static, "(oc in hand air)"], state, goal)
    with pytest.raises(PddlError, match="unknown predicate 'holding'"):
        planner.plan(objects, static, [*state, "(holding mug)"], goal)
    with pytest.raises(PddlError, match="unknown object 'spoon'"):
        planner.plan(objects, static, [*state, "(oc in hand spoon)"], goal)


def test_time_limits_name_the_phase() -> None:
    # grounding this task takes minutes by construction (tests/wide.py), so a 0.1 s limit
    # ends inside it on any machine, idle or loaded
    dom = parse_domain(wide.DOMAIN, source="wide")
    with pytest.raises(PlanningTimeout) as info:
        StatePlanner(dom).plan(
            *problem_atoms(dom, parse_problem(wide.problem())), deadline=Deadline.after(0.1)
        )
    assert info.value.phase == "grounding"
    planner = StatePlanner("utamp1")
    args = task_args(plan_scene(resolve_scene("pick-place/000"), "utamp1"))
    planner.plan(*args)  # grounded; now only the search runs
    with pytest.raises(PlanningTimeout) as info:
        planner.plan(*args, deadline=Deadline.after(1e-9))
    assert info.value.phase in ("sas", "search")


def test_sas_task_is_immutable_and_copies() -> None:
    on, off = Atom("on"), Atom("off")
    ops = [GroundOp("switch", (off,), (), (on,), (off,))]
    task = build_sas(ops, [off], [Literal(on)])
    again = copy.copy(task)
    assert again.text({off}) == task.text({off}) and "switch" in task.text({off})
    assert again != task and task == task  # compared by identity
    with pytest.raises(AttributeError, match="immutable"):
        task.solvable = False  # type: ignore[misc]


@pytest.mark.parametrize(
    "extra",
    [
        ("(oc on slot2 pan)",),  # slot2 holds air (the goal) and the pan: one SAS variable
        ("(not (oc in hand air))",),  # an atom and its negation
        ("(oc on slot2 pan)", "(oc on slot2 mug)"),
    ],
)
def test_contradictory_goal_is_unsolvable_like_fast_downwards_translator(
    gt: PlanOutcome, extra: tuple[str, ...]
) -> None:
    objects, static, state, goal = task_args(gt)
    assert StatePlanner("utamp2").plan(objects, static, state, goal).solved
    bad = [*goal, *extra]
    result = StatePlanner("utamp2").plan(objects, static, state, bad)
    assert not result.solved and "unsolvable" in (result.reason or "")
    text = gt.problem[: gt.problem.index("(:goal")] + "(:goal (and " + " ".join(bad) + ")))\n"
    for translator in fast_downward.TRANSLATORS:  # Fast Downward's own translator agrees
        res = fast_downward.solve(gt.domain, text, translator=translator)
        assert not res.solved and "unsolvable" in (res.reason or ""), translator


def test_contradictory_goal_literals_are_never_dropped() -> None:
    a, b, c = Atom("at", ("x", "a")), Atom("at", ("x", "b")), Atom("at", ("x", "c"))
    ops = [
        GroundOp(f"go-{p.args[1]}-{q.args[1]}", (p,), (), (q,), (p,))
        for p in (a, b, c)
        for q in (a, b, c)
        if p != q
    ]
    task = build_sas(ops, [a], [Literal(b)])
    assert task.solvable and task.n_groups == 1  # at x ?: one multi-valued variable
    assert not build_sas(ops, [a], [Literal(b), Literal(c)]).solvable
    assert not build_sas(ops, [a], [Literal(b), Literal(b, positive=False)]).solvable
    assert build_sas(ops, [a], [Literal(b), Literal(b)]).solvable  # a repeat is no conflict


def test_the_collector_pauses_for_grounding_and_collects_while_the_search_runs(
    gt: PlanOutcome, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No collection walks the ground task while it is built; the collection its objects
    set off comes once the search process runs (inside `processes.run`, after the start),
    not before the search starts; the collector is on again afterwards."""
    grounded: list[bool] = []
    real_task = StatePlanner._task

    def task(self, *args, **kwargs):
        grounded.append(gc.isenabled())
        return real_task(self, *args, **kwargs)

    def collected(phase: str, info: dict) -> None:
        if phase == "start" and grounded:
            stack = [f.name for f in traceback.extract_stack()]
            where.append("run" in stack and "search_sas" in stack)

    where: list[bool] = []
    monkeypatch.setattr(StatePlanner, "_task", task)
    planner = StatePlanner("utamp2")
    gc.callbacks.append(collected)
    try:
        result = planner.plan(*task_args(gt))
    finally:
        gc.callbacks.remove(collected)
    assert result.solved and grounded == [False] and gc.isenabled()
    assert where and where[0], where  # the first collection after grounding: in the search
    gc.disable()  # a caller's pause is left alone
    try:
        StatePlanner("utamp2").plan(*task_args(gt))
        assert not gc.isenabled()
    finally:
        gc.enable()
