"""The kitchen envs in symbolic grounding, parametrised over the registry (cf. Gymnasium's
tests/envs/test_envs.py): checkers, determinism, pickling, action errors, options."""

from __future__ import annotations

import pickle
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.registry import env_definitions, env_ids, load_definition, register_envs
from utamp_gym.errors import UnknownNameError

ENV_IDS = env_ids()


@pytest.fixture(scope="module", autouse=True)
def _registered() -> None:
    register_envs()


def make(env_id: str, **kwargs: Any) -> gym.Env:
    """Symbolic grounding and the grounded interface (an id may default to the objects one:
    tests/test_env_objects.py and tests/test_env_procedural.py check that)."""
    kwargs.setdefault("interface", "grounded")
    return gym.make(env_id, grounding="symbolic", **kwargs)


def masked_rollout(env: gym.Env, seed: int, steps: int) -> list[tuple[Any, ...]]:
    """(obs, reward, terminated, truncated, info) per step under seeded masked random actions."""
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed)
    out: list[tuple[Any, ...]] = [(obs, info)]
    for _ in range(steps):
        allowed = np.flatnonzero(info["action_mask"])
        # a scene may start at a dead end (procedural splits hold a few): any action ends it
        action = rng.choice(allowed) if allowed.size else 0
        obs, reward, terminated, truncated, info = env.step(action)
        out.append((obs, reward, terminated, truncated, info))
        if terminated or truncated:
            obs, info = env.reset()
            out.append((obs, info))
    return out


def test_registry_has_one_file_per_id() -> None:
    assert set(ENV_IDS) == {
        "UTampKitchen-v0",
        "UTampKitchenSlide-v0",
        "UTampKitchenProcedural-v0",
        "UTampKitchenGoals-v0",
    }
    for d in env_definitions():
        assert d.source.stem == d.id and d.max_episode_steps > 0
    assert register_envs() == ENV_IDS  # idempotent
    for d in env_definitions():
        spec = gym.spec(d.id)
        assert spec.entry_point == "utamp_gym.env.kitchen:UTampKitchenEnv"
        assert spec.max_episode_steps == d.max_episode_steps
        assert spec.kwargs == dict(load_definition(d.source).kwargs)


def test_bad_definition_file_is_reported(tmp_path: Any) -> None:
    (tmp_path / "Bad-v0.toml").write_text('id = "Other-v0"\nmax_episode_steps = 10\n')
    with pytest.raises(ValueError, match="must equal the file name"):
        env_definitions(tmp_path)
    (tmp_path / "Bad-v0.toml").write_text('id = "Bad-v0"\nmax_episode_steps = 0\n')
    with pytest.raises(ValueError, match="positive integer"):
        env_definitions(tmp_path)


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("extra", [{}, {"camera": True, "render_mode": "rgb_array"}])
def test_gymnasium_check_env(
    env_id: str, extra: dict[str, Any], session_display: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    env = make(env_id, **extra)
    # check_env makes the env once per declared render mode; "human" opens a window
    if session_display is not None:
        monkeypatch.setenv("DISPLAY", session_display.name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the checker's warnings count as failures
        check_env(env.unwrapped, skip_render_check=session_display is None)
    env.close()
    if session_display is None:
        pytest.skip("render modes not checked: 'human' needs a display (install Xvfb)")


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("camera", [False, True])
def test_sb3_check_env(env_id: str, camera: bool) -> None:
    env = make(env_id, camera=camera)
    sb3_check_env(env.unwrapped, warn=False)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_same_trajectories(env_id: str) -> None:
    a = masked_rollout(make(env_id), seed=7, steps=150)
    b = masked_rollout(make(env_id), seed=7, steps=150)
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert data_equivalence(x, y, exact=True)
    c = masked_rollout(make(env_id), seed=8, steps=150)
    assert not all(data_equivalence(x, y) for x, y in zip(a, c, strict=False))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_pickle_round_trip_mid_episode(env_id: str) -> None:
    env = make(env_id, num_objects=4)
    masked_rollout(env, seed=3, steps=5)
    clone = pickle.loads(pickle.dumps(env))
    assert clone.unwrapped.universe is env.unwrapped.universe  # shared through the cache
    assert clone.unwrapped.true_atoms() == env.unwrapped.true_atoms()
    rng = np.random.default_rng(0)
    for _ in range(20):
        action = rng.choice(np.flatnonzero(env.unwrapped.action_masks()))
        one, two = env.step(action), clone.step(action)
        assert data_equivalence(one, two, exact=True)
        if one[2] or one[3]:
            break


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("action", [-1, 10**6, 1.0, "0", True, None, np.array([0, 1])])
def test_malformed_actions_raise_value_error(env_id: str, action: Any) -> None:
    env = make(env_id)
    env.reset(seed=0)
    with pytest.raises(ValueError):
        env.step(action)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_failed_precondition_reports_and_changes_nothing(env_id: str) -> None:
    env = make(env_id)
    obs, info = env.reset(seed=1)
    action = int(np.flatnonzero(~info["action_mask"])[0])
    after, reward, terminated, truncated, info2 = env.step(action)
    assert info2["failure_reason"].startswith("precondition (")
    assert env.unwrapped.action_strings[action] in info2["failure_reason"]
    assert info2["action"] == env.unwrapped.action_strings[action]
    assert data_equivalence(obs, after, exact=True)
    assert (info2["action_mask"] == info["action_mask"]).all()
    assert (reward, terminated, truncated) == (0.0, False, False)


def test_terminate_on_failure_and_shaping() -> None:
    env = make("UTampKitchen-v0", terminate_on_failure=True, reward_shaping=True)
    _, info = env.reset(seed=1)
    _, reward, terminated, _, info = env.step(int(np.flatnonzero(~info["action_mask"])[0]))
    assert terminated and reward == pytest.approx(-0.01) and info["failure_reason"]


def test_action_space_is_stable_and_independent_of_filters() -> None:
    full = UTampKitchenEnv(suite="pick-place", grounding="symbolic")
    small = UTampKitchenEnv(suite="pick-place", grounding="symbolic", num_objects=2)
    fixed = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene="pick-place/003")
    assert full.action_strings == small.action_strings == fixed.action_strings
    assert list(full.action_strings) == sorted(full.action_strings)
    assert full.observation_space == small.observation_space
    assert {s.n_objects for s in small.scenes} == {2}
    fixed.reset(seed=0)
    assert fixed.scene.name == "pick-place/003"


def test_mask_hides_actions_of_absent_objects() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", num_objects=2)
    for seed in range(5):
        env.reset(seed=seed)
        absent = set(env.options.objects) - set(env.scene.object_names)
        for i in np.flatnonzero(env.action_masks()):
            assert not absent & set(env.action_strings[i].strip("()").split())


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"grounding": "mujoco"}, UnknownNameError, "physics, symbolic"),
        ({"domain": "utamp3"}, UnknownNameError, "utamp1, utamp2"),
        ({"affordances": "vlm"}, UnknownNameError, "gt, noisy, rules"),
        ({"num_objects": 1}, ValueError, "2..5"),
        ({"num_objects": 6}, ValueError, "2..5"),
        ({"num_objects": True}, ValueError, "2..5"),
        ({"noise": 1.5}, ValueError, r"\[0, 1\]"),
        ({"terminate_on_failure": "yes"}, ValueError, "True or False"),
        ({"render_mode": "ansi"}, UnknownNameError, "human, rgb_array, rgb_array_list"),
        ({"scene": "pick-place/999"}, UnknownNameError, "pick-place/000"),
        ({"scene": "pick-place/000", "num_objects": 5}, ValueError, "has 2 objects"),
        ({"image_size": (4, 4)}, ValueError, "8..4096"),
    ],
)
def test_options_are_validated(kwargs: dict[str, Any], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        UTampKitchenEnv(suite="pick-place", **{"grounding": "symbolic", **kwargs})


def test_reset_options() -> None:
    env = make("UTampKitchenSlide-v0")
    _, info = env.reset(seed=0, options={"scene": "sliding/004"})
    assert info["scene"] == "sliding/004"
    with pytest.raises(UnknownNameError, match="sliding/000"):
        env.reset(options={"scene": "pick-place/004"})
    with pytest.raises(UnknownNameError, match="scene"):
        env.reset(options={"bogus": 1})


def test_symbolic_poses_follow_the_effects() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene="pick-place/000")
    obs, _ = env.reset(seed=0)
    rows = {n: i for i, n in enumerate(env.options.objects)}
    scene = env.scene
    mover = next(n for n in scene.object_names if n != "tray")
    pick = next(
        i for i in np.flatnonzero(env.action_masks()) if env.action_strings[i].split()[1] == mover
    )
    obs, *_ = env.step(pick)
    place = next(
        i
        for i in np.flatnonzero(env.action_masks())
        if env.action_strings[i].startswith("(place-support") and " tray " in env.action_strings[i]
    )
    obs, *_ = env.step(place)
    tray, moved = obs["object_poses"][rows["tray"]], obs["object_poses"][rows[mover]]
    centre, height = scene.support_surface("tray", tray[:3].astype(float))
    box = scene.oriented_bbox(mover)
    assert moved[:2] + box.center[:2] == pytest.approx(centre, abs=1e-5)
    assert moved[2] + box.min[2] == pytest.approx(height, abs=1e-5)
    assert (obs["robot"] == env.reset(seed=0)[0]["robot"]).all()  # the robot stays home
    assert obs["present"][rows["tray"]] == 1 and obs["object_poses"][obs["present"] == 0].sum() == 0


def test_symbolic_render_is_a_schematic() -> None:
    env = make("UTampKitchen-v0", render_mode="rgb_array", render_size=(120, 160))
    env.reset(seed=0)
    image = env.render()
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8 and image.std() > 0


def test_missing_physics_backend_is_a_clear_error() -> None:
    with pytest.raises(ImportError, match="grounding='symbolic'"):
        gym.make("UTampKitchen-v0", backend="utamp_gym.no_such_module:Backend")
    with pytest.raises(ValueError, match="module:Class"):
        gym.make("UTampKitchen-v0", backend="no-colon")


def test_shaping_pays_each_new_tower_object_once() -> None:

    env = make("UTampKitchen-v0", reward_shaping=True, num_objects=5)
    policy = PlannerPolicy(env)
    obs, info = env.reset(seed=4)
    scene = env.unwrapped.scene
    start = len(scene.stacks[scene.slot_of("tray")]) - 1  # objects already on the tray
    total, terminated = 0.0, False
    while not terminated:
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        total += float(reward)
        assert not truncated
    assert total == pytest.approx(1.0 + 0.1 * (scene.n_objects - 1 - start))
