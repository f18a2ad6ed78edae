"""Tools around the kitchen envs (symbolic grounding): planner policy, PDDL-string wrapper,
vector envs, the dm_env adapter and the example script."""

from __future__ import annotations

import subprocess
import sys
import unittest
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from dm_env import StepType, test_utils
from procs import user_env
from solvable import solvable_resets

from utamp_gym.agents import PlannerPolicy
from utamp_gym.dm.adapter import DmEnvAdapter
from utamp_gym.env.registry import env_ids, register_envs
from utamp_gym.env.wrappers import SymbolicActionWrapper
from utamp_gym.errors import PlanningError, UnknownNameError

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module", autouse=True)
def _registered() -> None:
    register_envs()


def solvable_reset(env: gym.Env, seed: int) -> tuple[Any, dict[str, Any]]:
    """`reset(seed=...)` from `seed` on until the scene's goal is achievable."""
    for _, obs, info in solvable_resets(env, seed):
        return obs, info
    raise AssertionError("no solvable scene")


@pytest.mark.parametrize("env_id", env_ids())
def test_planner_policy_solves_a_five_object_scene(env_id: str) -> None:
    env = gym.make(env_id, grounding="symbolic", num_objects=5)
    policy = PlannerPolicy(env, "utamp2-gt", search="lama-first", timeout=60)
    obs, info = solvable_reset(env, 0)
    assert env.unwrapped.scene.n_objects == 5
    for _ in range(env.spec.max_episode_steps):
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        assert info["failure_reason"] == ""
        if terminated or truncated:
            break
    assert terminated and not truncated and reward == 1.0
    assert len(policy.planning_times) == 1 and policy.planning_times[0] > 0


def test_planner_policy_replans_after_a_deviation() -> None:
    env = gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=4)
    policy = PlannerPolicy(env)
    obs, info = env.reset(seed=3)
    obs, *_, info = env.step(policy(obs, info))
    # an off-plan action: the observed state is not the one the plan predicted
    off_plan = next(
        i
        for i in np.flatnonzero(info["action_mask"])
        if env.unwrapped.action_strings[i] != policy.plans[-1][1]
    )
    obs, *_, info = env.step(off_plan)
    terminated = False
    while not terminated:
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        assert not truncated
    assert reward == 1.0 and len(policy.planning_times) == 2


def test_planner_policy_rejects_bad_input() -> None:
    env = gym.make("UTampKitchen-v0", grounding="symbolic")
    with pytest.raises(UnknownNameError, match="utamp2-gt"):
        PlannerPolicy(env, "utamp3")
    with pytest.raises(UnknownNameError, match="lama-first"):
        PlannerPolicy(env, search="bfs")
    with pytest.raises(ValueError):
        PlannerPolicy(gym.make("CartPole-v1"))
    assert issubclass(PlanningError, Exception)


@pytest.mark.parametrize("env_id", env_ids())
def test_symbolic_action_wrapper_maps_a_plan(env_id: str) -> None:
    grounded = {"grounding": "symbolic", "num_objects": 5, "interface": "grounded"}
    env = gym.make(env_id, **grounded)
    policy = PlannerPolicy(env)
    obs, info = solvable_reset(env, 1)
    policy(obs, info)
    plan = policy.plans[-1]
    wrapped = SymbolicActionWrapper(gym.make(env_id, **grounded))
    wrapped.reset(seed=1, options={"scene": env.unwrapped.scene.name})
    for i, step in enumerate(plan):
        text = step.upper() if i % 2 else f"  {step}  "  # case and spacing do not matter
        _, reward, terminated, _, info = wrapped.step(text)
        assert info["failure_reason"] == "" and info["action"] == step
    assert terminated and reward == 1.0
    assert wrapped.action_string(wrapped.action(plan[0])) == plan[0]


def test_symbolic_action_wrapper_errors() -> None:
    wrapped = SymbolicActionWrapper(gym.make("UTampKitchen-v0", grounding="symbolic"))
    wrapped.reset(seed=0)
    with pytest.raises(UnknownNameError, match="ground action"):
        wrapped.step("(pick-support teapot teapot-body on left right back on slot1 under on)")
    for bad in ("pick-support salt", "(pick-support (salt))", "()", 3):
        with pytest.raises(ValueError):
            wrapped.step(bad)


def test_async_vector_env_runs() -> None:
    envs = gym.make_vec(
        "UTampKitchen-v0", num_envs=4, vectorization_mode="async", grounding="symbolic"
    )
    try:
        obs, info = envs.reset(seed=0)
        assert obs["symbolic"].shape[0] == 4 and info["action_mask"].shape[0] == 4
        rng = np.random.default_rng(0)
        for _ in range(5):
            masks = np.stack(envs.call("action_masks"))
            actions = np.array([rng.choice(np.flatnonzero(m)) for m in masks])
            obs, reward, _, _, info = envs.step(actions)
            assert reward.shape == (4,)
            assert all(r == "" for r in info["failure_reason"])
    finally:
        envs.close()


def test_dm_env_adapter_step_loop() -> None:
    env = DmEnvAdapter(gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=2), seed=0)
    step = env.reset()
    assert step.step_type == StepType.FIRST
    spec = env.observation_spec()
    for name, value in step.observation.items():
        spec[name].validate(value)
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(300):
        mask = step.observation["action_mask"]
        step = env.step(rng.choice(np.flatnonzero(mask)) if mask.any() else 0)
        if step.step_type == StepType.LAST:
            ends += 1
            assert step.discount in (0.0, 1.0)
    assert ends > 0
    env.close()


class DmEnvContractTest(test_utils.EnvironmentTestMixin, unittest.TestCase):
    """dm_env's own interface checks (specs, FIRST/MID/LAST, auto-reset)."""

    def make_object_under_test(self) -> DmEnvAdapter:
        return DmEnvAdapter(
            gym.make("UTampKitchen-v0", grounding="symbolic", max_episode_steps=8), seed=0
        )


def test_random_masked_agent_example_runs() -> None:
    out = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "random_masked_agent.py"), "--episodes", "2"],
        env=user_env(),
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert "episode 1" in out.stdout
