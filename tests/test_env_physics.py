"""The kitchen envs in physics grounding (MuJoCo backend)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.registry import env_ids, register_envs

pytestmark = [pytest.mark.physics, pytest.mark.slow]


@pytest.fixture(scope="module", autouse=True)
def _registered() -> None:
    register_envs()


@pytest.mark.parametrize("env_id", env_ids())
def test_gymnasium_check_env_physics(
    env_id: str, session_display: object, monkeypatch: pytest.MonkeyPatch
) -> None:
    probe = gym.make(env_id, grounding="symbolic")  # the id's smallest scenes (2 or 3 objects)
    fewest = min(scene.n_objects for scene in probe.unwrapped.scenes)  # type: ignore[attr-defined]
    probe.close()
    env = gym.make(env_id, num_objects=fewest)
    # check_env makes the env once per declared render mode; "human" opens a MuJoCo viewer
    if session_display is not None:
        monkeypatch.setenv("DISPLAY", session_display.name)  # type: ignore[attr-defined]
    check_env(env.unwrapped, skip_render_check=session_display is None)
    env.close()
    if session_display is None:
        pytest.skip("render modes not checked: 'human' needs a display (install Xvfb)")


def test_physics_observations_come_from_the_backend() -> None:
    env = gym.make(
        "UTampKitchen-v0", num_objects=3, camera=True, image_size=(64, 80), record_timings=True
    )
    obs, info = env.reset(seed=0)
    kitchen = env.unwrapped
    rows = {n: i for i, n in enumerate(kitchen.options.objects)}
    for name, pose in kitchen.backend.object_poses().items():
        assert obs["object_poses"][rows[name]] == pytest.approx(pose, abs=1e-6)
    assert obs["object_poses"][obs["present"] == 0].sum() == 0
    assert obs["robot"].shape == (9,) and obs["image"].shape == (64, 80, 3)
    action = int(np.flatnonzero(info["action_mask"])[0])
    _, _, _, _, info = env.step(action)
    assert info["macro_result"]["executed"] and "step_s" in info["timings"]
    env.close()


def test_planner_policy_solves_a_three_object_scene_in_physics() -> None:
    env = gym.make("UTampKitchen-v0", num_objects=3)
    policy = PlannerPolicy(env)
    obs, info = env.reset(seed=0)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
    assert terminated and reward == 1.0, info["failure_reason"]
    env.close()
