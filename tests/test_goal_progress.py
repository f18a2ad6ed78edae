"""What the tower used to decide, read from the scene's goal (issue #38): the env's reward
shaping (progress towards the goal's literals), the dm_control task's reward and success, and
the why-not explanations of an unsolvable goal (its blocked literals)."""

from __future__ import annotations

import gymnasium as gym
import pytest

from utamp_gym.affordances.sources import ground_truth_for
from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.registry import register_envs
from utamp_gym.env.task import PROGRESS_BONUS, TOWER, progress
from utamp_gym.eval.blocking import goal_blocks
from utamp_gym.eval.explain import explain_unsolvable
from utamp_gym.suites import resolve_scene
from utamp_gym.suites.procedural_v2 import split_scenes
from utamp_gym.tasks.goal import CUSTOM, Goal, negated, unmet
from utamp_gym.tasks.success import literals_held
from utamp_gym.tasks.templates import tower_goal

register_envs()
ENV_ID = "UTampKitchenProcedural-v0"
SPLIT = "procedural-v2/test-tasks"


def _non_tower_scene(n_unmet: int = 2) -> str:
    """An achievable test-tasks scene whose goal has at least `n_unmet` unmet literals."""
    for i, s in enumerate(split_scenes("test-tasks")):
        if s.achievable and s.template != TOWER and s.plan_length >= 2 * n_unmet:
            return f"{SPLIT}/{i:04d}"
    raise AssertionError("no such scene")


def test_progress_counts_literals_except_for_the_papers_tower() -> None:
    goal = Goal(CUSTOM, (), ("(oc in hand air)", "(oc on slot2 air)"))
    assert progress(goal, held=2, tower_height=5) == 2
    tower = resolve_scene("pick-place/000")
    assert progress(tower_goal(tower), held=2, tower_height=5) == 5


def _shaped_episode(grounding: str, scene: str) -> tuple[float, int, int]:
    """(total reward, goal literals, literals holding at reset) of the planner's episode."""
    env = gym.make(ENV_ID, split=SPLIT, scene=scene, grounding=grounding, reward_shaping=True,
                   interface="grounded")  # fmt: skip
    obs, info = env.reset(seed=0)
    u = env.unwrapped
    goal = u.goal
    atoms = u.true_atoms() if grounding == "symbolic" else u.perception.atoms
    start = len(goal.literals) - len(unmet(goal, atoms))
    policy = PlannerPolicy(env)
    total, terminated, steps = 0.0, False, 0
    while not terminated and steps < 40:
        obs, reward, terminated, _, info = env.step(policy(obs, info))
        total += float(reward)
        steps += 1
    assert info["is_success"], info["failure_reason"]
    env.close()
    return total, len(goal.literals), start


def test_symbolic_shaping_pays_each_goal_literal_once_on_a_non_tower_goal() -> None:
    scene = _non_tower_scene()
    total, n, start = _shaped_episode("symbolic", scene)
    assert start < n  # the goal did not hold at the start
    assert total == pytest.approx(1.0 + PROGRESS_BONUS * (n - start))


@pytest.mark.physics
def test_physics_shaping_counts_the_perceived_goal_literals() -> None:
    scene = _non_tower_scene()
    total, n, start = _shaped_episode("physics", scene)
    assert start < n
    assert total == pytest.approx(1.0 + PROGRESS_BONUS * (n - start))


@pytest.mark.physics
def test_dm_task_reward_and_success_are_the_scenes_goal() -> None:
    dm = pytest.importorskip("utamp_gym.dm", reason="the dm extra (dm-control)")
    env = dm.load(scene=_non_tower_scene(), seed=0)
    env.reset()
    task = env.task
    goal = task.goal
    assert goal is not None and goal.template != TOWER
    perception = task.perception(env.physics)
    held = literals_held(goal, perception.atoms)
    assert 0 < held < len(goal.literals)
    assert task.get_reward(env.physics) == pytest.approx(held / len(goal.literals))
    assert not task.goal_reached(env.physics) and task.get_termination(env.physics) is None
    holding = tuple(sorted(a for a in perception.atoms if a.startswith("(oc on slot")))[:2]
    task.goal = Goal(CUSTOM, (), holding)  # literals that hold now: the goal is reached
    assert task.goal_reached(env.physics) and task.get_termination(env.physics) == 0.0
    assert task.get_reward(env.physics) == 1.0
    task.goal = Goal(CUSTOM, (), (negated(holding[0]),))
    assert not task.goal_reached(env.physics)


def test_unsolvable_goals_are_explained_by_their_literals() -> None:
    unachievable = [s for s in split_scenes("test-tasks") if not s.achievable]
    explained = 0
    for s in unachievable:
        scene = s.scene
        e = explain_unsolvable(scene, ground_truth_for(scene))
        assert not e.found
        assert set(e.blocked_atoms) <= set(scene.goal.literals), scene.name
        explained += bool(e.blocking)
        if e.blocking:
            assert e.rest_solvable is not None
            stages = {b.stage for b in e.blocking}
            # a move's rule, or (every move possible on its own) the order of the moves
            assert stages <= {"pick", "stand", "place"} or stages == {"order"}
    assert explained == len(unachievable)


def test_goal_blocks_name_the_sort_goals_literal_and_its_rule() -> None:
    s = next(s for s in split_scenes("test-tasks") if not s.achievable and s.template == "sort")
    blocks = goal_blocks(s.scene, ground_truth_for(s.scene), s.scene.goal)
    assert blocks
    for b in blocks:
        assert b.atom in s.scene.goal.literals and b.refusal.rule and b.refusal.detail
        assert b.object in s.scene.object_names
    # the paper's scenes keep their tower explanation: no goal of their own
    assert resolve_scene("pick-place/000").goal is None
