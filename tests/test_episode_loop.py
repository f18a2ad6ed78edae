"""The one episode loop (`utamp_gym.agents.run_policy`): policies acting through ``env.step``.

Every `utamp eval` run in either grounding (each planning method and VLM method open loop,
each planning method closed loop, a saved ``rl:PATH`` agent) must call ``env.step`` once per
macro action in its row, and its row's success must be the env's last ``info["is_success"]``.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import pytest
from test_eval_vlm import Server, attributes, completion, fenced, vlm  # noqa: F401 (fixture)

from utamp_gym.agents import OpenLoopPolicy, PlannerPolicy, PlanStopped, run_policy
from utamp_gym.agents.runs import execute_plan
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.errors import PlanningError
from utamp_gym.eval.records import PLAN_SEPARATOR
from utamp_gym.eval.runner import EVAL_METHODS, EvalTask, run_task
from utamp_gym.eval.summary import failure_category
from utamp_gym.planning.methods import METHODS, plan_scene
from utamp_gym.suites import resolve_scene

SCENE = "pick-place/003"


class StepSpy:
    """Counts `UTampKitchenEnv.step` calls and keeps the last info."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.calls, self.last_info = 0, None
        original = UTampKitchenEnv.step

        def step(env: UTampKitchenEnv, action: Any) -> Any:
            out = original(env, action)
            self.calls += 1
            self.last_info = out[4]
            return out

        monkeypatch.setattr(UTampKitchenEnv, "step", step)


def test_open_loop_policy_plays_the_plan_and_stops_at_its_end() -> None:
    scene = resolve_scene(SCENE)
    plan = plan_scene(scene, "utamp2-gt").plan
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=scene.name)
    ep = run_policy(env, OpenLoopPolicy(env, plan), max_steps=40, seed=0)
    assert ep.actions == tuple(plan)
    assert ep.success and ep.ended == "terminated" and ep.info["is_success"]


def test_open_loop_policy_stops_at_the_first_failure() -> None:
    scene = resolve_scene(SCENE)
    plan = list(plan_scene(scene, "utamp2-gt").plan)
    bad = [plan[1], *plan]  # a place before anything is held: fails, and the plan stops
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=scene.name)
    ep = run_policy(env, OpenLoopPolicy(env, bad), max_steps=40, seed=0)
    assert ep.actions == (bad[0],) and ep.n_failed == 1 and not ep.success
    assert ep.ended == "policy" and ep.stopped.startswith(f"step 0 {bad[0]}: precondition")
    with pytest.raises(PlanStopped):
        OpenLoopPolicy(env, [])(None, {"action": ""})


def test_planner_policy_in_the_loop_reaches_the_goal() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=SCENE)
    ep = run_policy(env, PlannerPolicy(env), max_steps=40, seed=1)
    assert (
        ep.success
        and ep.n_failed == 0
        and len(ep.actions) == len(plan_scene(resolve_scene(SCENE), "utamp2-gt").plan)
    )


@pytest.mark.parametrize("method", METHODS)
def test_every_closed_loop_method_steps_the_env_once_per_action(
    method: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    spy = StepSpy(monkeypatch)
    row = run_task(EvalTask(SCENE, method, seed=0, grounding="symbolic", closed_loop=True))
    assert not row.crashed, row.failure_reason
    assert spy.calls == row.plan_length > 0
    assert spy.last_info is not None and row.success == spy.last_info["is_success"]
    assert len(row.plan.split(PLAN_SEPARATOR)) == row.plan_length


VLM_SCENE = "pick-place/013"  # tray/pan | board (the VLM tests' scene)


@pytest.mark.parametrize("grounding", ["physics", "symbolic"])
@pytest.mark.parametrize("method", EVAL_METHODS)
def test_every_open_loop_method_steps_the_env_once_per_action(
    method: str,
    grounding: str,
    monkeypatch: pytest.MonkeyPatch,
    vlm: Server,  # noqa: F811
) -> None:
    vlm.reply(completion(fenced(attributes(VLM_SCENE))))
    plan = ["pick cutting-board table", "place cutting-board frying-pan"]
    vlm.reply(completion(fenced({"plan": plan})))
    spy = StepSpy(monkeypatch)
    noise = 0.0 if grounding == "physics" else None
    task = EvalTask(VLM_SCENE, method, seed=0, grounding=grounding, pose_noise=noise)
    row = run_task(task)
    assert not row.crashed and row.solved, row.failure_reason
    assert spy.last_info is not None and row.success == spy.last_info["is_success"]
    if spy.calls < row.plan_length:  # open loop: the plan stopped at its first failed step
        assert not row.success and spy.calls > 0
        assert row.failure_reason.endswith(spy.last_info["failure_reason"])
    else:
        assert spy.calls == row.plan_length > 0


def test_symbolic_open_loop_row_names_the_failed_step_and_its_false_literal(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """utamp1 ignores the affordances: its plan is played until the outcome model refuses a
    step, and the row says which step and which ground-truth literal."""
    spy = StepSpy(monkeypatch)
    row = run_task(EvalTask(SCENE, "utamp1", seed=0, grounding="symbolic"))
    assert row.solved and not row.success and row.valid_gt is False
    assert spy.last_info is not None and 0 < spy.calls <= row.plan_length
    step = spy.calls - 1
    action = row.plan.split(PLAN_SEPARATOR)[step]
    assert row.failure_reason == f"step {step} {action}: {spy.last_info['failure_reason']}"
    assert "(ground truth)" in row.failure_reason
    assert failure_category(row.failure_reason) == "invalid plan: violates canGraspFrom"


def test_a_plan_step_outside_the_env_domain_fails_there() -> None:
    scene = resolve_scene(SCENE)
    plan = [plan_scene(scene, "utamp2-gt").plan[0], "(slide-edge cutting-board table)"]
    ex = execute_plan(SCENE, plan, grounding="symbolic")
    assert not ex.success and [s.success for s in ex.steps] == [True]
    assert ex.failure_reason == f"step 1 {plan[1]}: not an action of the env's domain (utamp2)"


def test_planner_policy_old_path_warns() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        from utamp_gym.env import planner_policy

        assert planner_policy.PlannerPolicy is PlannerPolicy
    assert any(issubclass(w.category, DeprecationWarning) for w in caught)


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("sb3_contrib")
    from utamp_gym.rl.train import train

    out = tmp_path_factory.mktemp("tiny")
    train(
        algo="maskable-ppo", num_objects=2, steps=256, n_envs=1, seed=0, out=out,
        eval_every=10_000, eval_episodes=1, progress=False,
    )  # fmt: skip
    return out / "model.zip"


def test_rl_method_steps_the_env_once_per_action(
    tiny_model: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    spy = StepSpy(monkeypatch)
    row = run_task(EvalTask("pick-place/000", f"rl:{tiny_model}", seed=0, grounding="symbolic"))
    assert not row.crashed, row.failure_reason
    assert spy.calls == row.plan_length > 0
    assert spy.last_info is not None and row.success == spy.last_info["is_success"]


def test_planner_policy_replans_without_a_step_outside_the_env_action_space(monkeypatch) -> None:
    """A plan step the env cannot take (a method believing other affordances than the env's,
    e.g. perceived ones) is left out and the planner asked again; only when every plan needs
    such steps does the policy give up, naming them."""
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=SCENE)
    policy = PlannerPolicy(env)
    env.reset(seed=1)
    good = plan_scene(resolve_scene(SCENE), "utamp2-gt").plan
    bogus = "(pick-support tray tray-rim on front back back on slot1 under on)"
    asked: list[frozenset[str]] = []

    def steps(bits: int, exclude: frozenset[str]) -> tuple[str, ...]:
        asked.append(exclude)
        return tuple(good) if bogus in exclude else (bogus, *good[1:])

    monkeypatch.setattr(policy, "_plan_steps", steps)
    ids = policy._replan(0, frozenset())
    assert [env.universe.actions[i] for i in ids] == list(good)
    assert asked == [frozenset(), frozenset({bogus})]
    monkeypatch.setattr(policy, "_plan_steps", lambda bits, exclude: (bogus,))
    with pytest.raises(PlanningError, match="not in the env's action space"):
        policy._replan(0, frozenset())
