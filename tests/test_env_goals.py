"""The env reads goals: the scene's (default: the paper's tower), the ``task`` option, negated
literals in symbolic success, ``info["goal"]`` / ``info["instruction"]`` and the planner
policy's problem."""

from __future__ import annotations

import pickle
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import data_equivalence

from utamp_gym.agents import PlannerPolicy, state_problem
from utamp_gym.agents.runs import execute_plan
from utamp_gym.env.goals import resolve_goal
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.object_goal import GOAL_KEYS
from utamp_gym.env.object_space import MAX_OBJECTS, N_ACTIONS, n_actions, n_entities
from utamp_gym.env.registry import register_envs
from utamp_gym.errors import UnknownNameError
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.geometry import PARTS
from utamp_gym.suites import resolve_scene, suite_scenes
from utamp_gym.symbolic.problem import goal_atoms
from utamp_gym.tasks.goal import CUSTOM, Goal, goal_holds, split_literal
from utamp_gym.tasks.language import instruction
from utamp_gym.tasks.templates import tower_goal

SCENE = "pick-place/105"  # the mug stands on the board at the start


@pytest.fixture(scope="module", autouse=True)
def _registered() -> None:
    register_envs()


def symbolic(**kwargs: object) -> UTampKitchenEnv:
    return UTampKitchenEnv(suite="pick-place", grounding="symbolic", **kwargs)  # type: ignore[arg-type]


def solve(env: gym.Env, seed: int, steps: int = 40) -> dict:
    obs, info = env.reset(seed=seed)
    policy = PlannerPolicy(env)
    for _ in range(steps):
        obs, _, terminated, truncated, info = env.step(policy(obs, info))
        if terminated or truncated:
            break
    return info


def test_default_goal_is_the_papers_tower_with_its_instruction() -> None:
    env = symbolic()
    for seed in range(3):
        _, info = env.reset(seed=seed)
        scene = env.scene
        assert scene.goal is None and env.goal == tower_goal(scene)
        assert info["goal"] == goal_atoms(scene)
        assert info["instruction"] == instruction(scene, tower_goal(scene))
        assert "tray" in info["instruction"]
    info = solve(env, 0)
    assert info["is_success"] and info["goal"] == goal_atoms(env.scene)


def test_negated_goal_literals_must_hold_for_success() -> None:
    holds = Goal.make(CUSTOM, {}, ["(oc in hand air)"])
    env = symbolic(scene=SCENE, task=holds)
    _, info = env.reset(seed=0)
    assert info["is_success"]  # the hand is empty at the start
    assert info["instruction"] == "make these hold: (oc in hand air)"
    moved = Goal.make(CUSTOM, {}, ["(oc in hand air)", "(not (oc on board mug))"])
    env = symbolic(scene=SCENE, task=moved)
    _, info = env.reset(seed=0)
    assert not info["is_success"] and env.goal == moved
    assert info["goal"] == ("(oc in hand air)", "(not (oc on board mug))")
    info = solve(env, 0)
    assert info["is_success"] and "(oc on board mug)" not in env.true_atoms()


def test_task_template_draws_one_goal_per_scene_and_the_planner_follows_it() -> None:
    env = symbolic(task="clear")
    assert 0 < len(env.scenes) <= len(symbolic().scenes)  # scenes without a surface to clear out
    _, info = env.reset(seed=3)
    assert env.goal.template == "clear" and info["goal"] == env.goal.literals
    assert env.goal == resolve_goal(env.scene, "clear")  # a pure function of (scene, task)
    assert info["instruction"] == instruction(env.scene, env.goal)
    info = solve(env, 3)
    assert info["is_success"] and goal_holds(env.goal, env.true_atoms())


def test_templated_goal_is_rebuilt_in_each_scene() -> None:
    scene = resolve_scene(SCENE)
    goal = resolve_goal(scene, "clear")
    assert goal is not None
    env = symbolic(task=goal)
    assert SCENE in {s.name for s in env.scenes}
    assert all(resolve_goal(s, goal) is not None for s in env.scenes)
    env.reset(seed=0, options={"scene": SCENE})
    assert env.goal == goal


def test_task_option_errors_name_the_valid_templates() -> None:
    with pytest.raises(UnknownNameError, match=r"goal template.*put-on"):
        symbolic(task="put-onn")
    with pytest.raises(ValueError, match="task must be"):
        symbolic(task=3)
    nowhere = Goal.make("put-on", {"object": "kettle", "target": "tray"}, ["(oc in hand air)"])
    with pytest.raises(ValueError, match="no goal in any of the env's"):
        symbolic(task=nowhere)


def test_planner_problem_and_pickled_env_carry_the_goal() -> None:
    env = symbolic(task="put-on")
    first = env.reset(seed=1)
    problem = state_problem(env.scene, ["mug"], [], "utamp2", goal=env.goal.literals)
    assert all(lit in problem for lit in env.goal.literals)
    assert goal_atoms(env.scene)[1] in state_problem(env.scene, ["mug"], [], "utamp2")
    again = pickle.loads(pickle.dumps(env))
    assert data_equivalence(again.reset(seed=1), first) and again.goal == env.goal


def test_gym_make_passes_task() -> None:
    env = gym.make("UTampKitchen-v0", grounding="symbolic", task="tower")
    _, info = env.reset(seed=0)
    assert env.unwrapped.goal == tower_goal(env.unwrapped.scene)  # type: ignore[attr-defined]
    assert info["goal"] == goal_atoms(env.unwrapped.scene)  # type: ignore[attr-defined]


@pytest.mark.physics
@pytest.mark.slow
def test_physics_success_is_the_goal_on_the_measured_state() -> None:
    moved = Goal.make(CUSTOM, {}, ["(oc in hand air)", "(not (oc on board mug))"])
    env = UTampKitchenEnv(suite="pick-place", scene=SCENE, task=moved)
    _, info = env.reset(seed=0)
    assert not info["is_success"]
    info = solve(env, 0, steps=6)
    perception = env.perception
    assert perception is not None and "(oc on board mug)" not in perception.atoms
    assert info["is_success"] and info["goal"] == moved.literals
    env.close()


def test_procedural_v2_split_env_reads_each_scenes_goal() -> None:
    env = gym.make(
        "UTampKitchenProcedural-v0", split="procedural-v2/test-tasks", grounding="symbolic"
    )
    kitchen = env.unwrapped
    assert kitchen.options.suite == "procedural-v2/test-tasks"  # type: ignore[attr-defined]
    templates = set()
    for seed in range(8):
        _, info = env.reset(seed=seed)
        scene = kitchen.scene  # type: ignore[attr-defined]
        assert scene.goal is not None and kitchen.goal == scene.goal  # type: ignore[attr-defined]
        assert info["goal"] == scene.goal.literals
        assert info["instruction"] == instruction(scene, scene.goal)
        templates.add(scene.goal.template)
    assert len(templates) >= 2 and "tower" not in templates  # held-out templates only


def test_test_count_grows_the_objects_interface_to_eight_slots() -> None:
    """The objects interface fits the split: 8 slots (and pose rows) for test-count's 8-object
    scenes, the default 6 where every scene fits; fewer slots than a scene is refused by
    name; the grounded interface still needs the rows given."""
    big = next(s.name for s in suite_scenes("procedural-v2/test-count") if s.n_objects == 8)
    env = gym.make("UTampKitchenGoals-v0", split="procedural-v2/test-count", grounding="symbolic")
    kitchen = env.unwrapped
    assert kitchen.options.slots == 8  # type: ignore[attr-defined]
    assert env.action_space == gym.spaces.Discrete(n_actions(8)) != gym.spaces.Discrete(N_ACTIONS)
    obs, _ = env.reset(seed=0, options={"scene": big})
    assert obs["present"].shape == (8,) and obs["present"].sum() == 8
    assert obs["goal_contact"].shape == (n_entities(8), n_entities(8), 7)
    assert env.observation_space.contains(obs)
    assert sorted(kitchen.objects.slots.values()) == list(range(8))  # type: ignore[attr-defined]
    assert gym.make("UTampKitchenGoals-v0", grounding="symbolic").unwrapped.options.slots == 6  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match="more than slots=6: use slots=8"):
        gym.make("UTampKitchenGoals-v0", split="procedural-v2/test-count", slots=6)
    with pytest.raises(ValueError, match=r"slots .* with interface='objects'"):
        gym.make("UTampKitchenGoals-v0", interface="grounded", slots=8)
    with pytest.raises(ValueError, match="outside the env's observation rows"):
        gym.make("UTampKitchenProcedural-v0", split="procedural-v2/test-count",
                 interface="grounded")  # fmt: skip
    rows = ["base", *(f"obj{i}" for i in range(1, 8))]
    env = gym.make(
        "UTampKitchenProcedural-v0", split="procedural-v2/test-count", objects=rows,
        grounding="symbolic", interface="grounded",
    )  # fmt: skip
    env.reset(options={"scene": big})
    assert env.unwrapped.scene.n_objects == 8  # type: ignore[attr-defined]


def test_more_slots_leave_the_rest_empty_and_pad_smaller_scenes() -> None:
    """A train scene in an 8-slot interface: its objects in 8 slots, the same relations."""
    six = gym.make("UTampKitchenGoals-v0", grounding="symbolic")
    eight = gym.make("UTampKitchenGoals-v0", grounding="symbolic", slots=8)
    for seed in range(3):
        o6, i6 = six.reset(seed=seed)
        o8, i8 = eight.reset(seed=seed)
        assert i6["goal"] == i8["goal"] and o8["present"].shape == (8,)
        assert o6["present"].sum() == o8["present"].sum()
        assert o6["goal_contact"].sum() == o8["goal_contact"].sum()
        assert i6["action_mask"].sum() == i8["action_mask"].sum()


def _entity(env: UTampKitchenEnv, name: str) -> int:
    """The observation's entity index of an object (its slot) or a table region."""
    slots = env._objects.slots  # type: ignore[union-attr]
    if name in slots:
        return slots[name]
    regions = [s.name for s in env.scene.slots]
    return MAX_OBJECTS + regions.index(name)


def test_goal_observation_writes_every_literal_in_slot_order() -> None:
    env = gym.make("UTampKitchenGoals-v0", grounding="symbolic")
    kitchen = env.unwrapped
    assert isinstance(kitchen, UTampKitchenEnv)
    v0 = gym.make("UTampKitchenProcedural-v0", grounding="symbolic").observation_space
    assert set(env.observation_space.spaces) == {*v0.spaces, *GOAL_KEYS}  # type: ignore[attr-defined]
    for seed in range(6):
        obs, _ = env.reset(seed=seed)
        assert env.observation_space.contains(obs)
        expected = {k: np.zeros_like(obs[k]) for k in GOAL_KEYS}
        for lit in kitchen.goal.literals:
            positive, body = split_literal(lit)
            part, a, b = body[1:-1].split()[1:]
            if a == "hand":
                continue  # the hand-empty literal: `held` shows it
            sign = "goal_" if positive else "goal_not_"
            if b == "air":
                expected[sign + "free"][_entity(kitchen, a), PARTS.index(part)] = 1
            else:
                at = (_entity(kitchen, a), _entity(kitchen, b), PARTS.index(part))
                expected[sign + "contact"][at] = 1
        for k in GOAL_KEYS:
            assert np.array_equal(obs[k], expected[k]), (seed, k)
        assert obs["goal_not_contact"].any() or obs["goal_contact"].any() or obs["goal_free"].any()
        step = env.step(int(np.flatnonzero(kitchen.action_masks())[0]))
        assert all(np.array_equal(step[0][k], obs[k]) for k in GOAL_KEYS)  # fixed per episode


def test_grounded_goal_observation_is_the_goals_atoms() -> None:
    env = symbolic(goal_observation=True, scene=SCENE, task=Goal.make(
        CUSTOM, {}, ["(oc in hand air)", "(not (oc on board mug))"]))  # fmt: skip
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    atoms = env.symbolic_atoms
    assert [atoms[i] for i in np.flatnonzero(obs["goal"])] == ["(oc in hand air)"]
    assert [atoms[i] for i in np.flatnonzero(obs["goal_not"])] == ["(oc on board mug)"]
    assert "goal" not in symbolic().observation_space.spaces  # default: v0's spaces


@pytest.mark.physics
@pytest.mark.slow
def test_open_loop_failure_names_the_unmet_goal_literals() -> None:
    scene = resolve_scene("procedural-v2/test-tasks/0000")
    assert scene.goal is not None and scene.goal.template != "tower"
    outcome = plan_scene(scene, "utamp2-gt")
    assert outcome.solved and outcome.plan_length > 2
    run = execute_plan(scene, outcome.plan[:2])
    assert not run.success and run.failure is not None
    assert run.failure["reason"].startswith("goal not reached: (")
    named = run.failure["reason"].removeprefix("goal not reached: ").split(", ")
    assert named and set(named) <= set(scene.goal.literals)


def test_readme_goals_snippet_reports_its_goal_and_the_planner_reaches_it() -> None:
    """The README's procedural-v2 snippet runs as printed: the instruction it quotes is the
    env's, and its planner policy reaches the goal of that episode."""
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    (snippet,) = [
        b for b in re.findall(r"```python\n(.*?)```", text, re.DOTALL) if "UTampKitchenGoals" in b
    ]
    ns: dict[str, object] = {}
    exec(compile(snippet, "README.md", "exec"), ns)
    env, info, policy = ns["env"], ns["info"], ns["policy"]
    quoted = re.search(r'info\["instruction"\]\s+# \'(.*)\'', snippet)
    assert quoted is not None and info["instruction"] == quoted.group(1)
    assert info["goal"] == env.unwrapped.goal.literals
    obs = ns["obs"]
    for _ in range(40):
        obs, _, terminated, truncated, info = env.step(policy(obs, info))
        if terminated or truncated:
            break
    assert terminated and info["is_success"]
