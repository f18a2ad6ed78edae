"""Gymnasium's generic env tests, ported: every registered id in both groundings.

Gymnasium runs these on each of its own envs (``tests/envs/test_envs.py``: the env checker,
the passive checker, a determinism rollout comparing observations *and* info, pickling;
``tests/envs/test_rendering.py``: every render mode but "human"; ``tests/vector``: async and
sync vector envs agree). Here they run over `utamp_gym.env.registry.env_ids()`, so an id added
later gets them without a line changed, in physics and in symbolic grounding. Plus what the
kitchen envs promise on top: out-of-range and malformed actions raise `ValueError`, a pickled
or deep-copied physics env steps exactly as the original, and ``info["is_success"]``.

Physics runs on a two-object scene of each id (``num_objects=2``) to keep the suite quick.
`VARIANTS` adds registered ids with options of their own (the procedural env on a
procedural-v2 split, whose scenes carry their goals; its smallest scenes have 3 objects; the
goals env on test-count's 8-object scenes, whose objects interface has 8 slots).
"""

from __future__ import annotations

import copy
import itertools
import pickle
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence
from gymnasium.vector import AsyncVectorEnv, SyncVectorEnv
from solvable import solvable_resets

from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.registry import env_ids, register_envs
from utamp_gym.planning.methods import plan_scene
from utamp_gym.rl.envs import make_env

register_envs()
GROUNDINGS = ("physics", "symbolic")
#: test id -> (registered id, its options, num_objects of its physics runs)
VARIANTS: dict[str, tuple[str, dict[str, Any], int]] = {
    "UTampKitchenProcedural-v0[procedural-v2/test-tasks]": (
        "UTampKitchenProcedural-v0",
        {"split": "procedural-v2/test-tasks"},
        3,
    ),
    # the objects interface grown to 8 slots, on the split's 8-object scenes
    "UTampKitchenGoals-v0[procedural-v2/test-count, 8 objects]": (
        "UTampKitchenGoals-v0",
        {
            "split": "procedural-v2/test-count",
            "num_objects": 8,
            "domain": "utamp2x",
            "affordances": "rules",
        },
        8,
    ),
}
#: registered ids whose smallest scenes have more than 2 objects (procedural-v2's have 3)
SMALLEST = {"UTampKitchenGoals-v0": 3}
IDS = (*env_ids(), *VARIANTS)
CASES = [
    pytest.param(env_id, grounding, id=f"{env_id}-{grounding}")
    for env_id in IDS
    for grounding in GROUNDINGS
]
PHYSICS = [pytest.param(env_id, id=env_id) for env_id in IDS]
#: Gymnasium's own list (tests/envs/test_envs.py): our Box spaces are bounded, so none is expected
CHECK_ENV_IGNORE_WARNINGS: tuple[str, ...] = ()
SEED = 0


def variant(env_id: str, grounding: str | None = None) -> tuple[str, dict[str, Any]]:
    """(registered id, options) of a test id; physics (`grounding`) on its smallest scenes."""
    real, options, small = VARIANTS.get(env_id, (env_id, {}, SMALLEST.get(env_id, 2)))
    if grounding == "physics":
        options = {**options, "num_objects": small}
    return real, options


def make(env_id: str, grounding: str, **kwargs: Any) -> gym.Env:
    """The id in `grounding`; physics on its two-object scenes (`VARIANTS`: their own)."""
    real, options = variant(env_id, grounding)
    return gym.make(real, grounding=grounding, **options, **kwargs)


def masked(env: gym.Env, info: dict[str, Any]) -> np.int64:
    """A random action the mask allows, from the env's action space's generator."""
    return env.action_space.sample(mask=info["action_mask"].astype(np.int8))


# ---------------------------------------------------------------- tests/envs/test_envs.py
@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_env_checker(env_id: str, grounding: str) -> None:
    """`test_all_env_api`: the checker, with no warning but the expected ones (Gymnasium
    skips the render check here; the render modes are the next tests')."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = make(env_id, grounding).unwrapped
        check_env(env, skip_render_check=True)
        env.close()
    unexpected = [str(w.message) for w in caught if str(w.message) not in CHECK_ENV_IGNORE_WARNINGS]
    assert not unexpected


@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_passive_env_checker(env_id: str, grounding: str) -> None:
    """`test_all_env_passive_env_checker`: made, reset and stepped through `gym.make`'s
    passive checker without a warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = make(env_id, grounding)
        env.reset(seed=SEED)
        env.step(env.action_space.sample())
        env.close()
    assert not [str(w.message) for w in caught]


def _steps(grounding: str) -> int:
    return 50 if grounding == "symbolic" else 8


@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_env_determinism_rollout(env_id: str, grounding: str) -> None:
    """`test_env_determinism_rollout`: two envs, one seed, equal observations, rewards,
    flags *and info* at every step. Gymnasium samples unmasked actions (mostly failing
    preconditions here); every other step samples a masked one, so physics runs too."""
    env_1, env_2 = (make(env_id, grounding, disable_env_checker=True) for _ in range(2))
    obs_1, info_1 = env_1.reset(seed=SEED)
    obs_2, info_2 = env_2.reset(seed=SEED)
    assert data_equivalence(obs_1, obs_2, exact=True)
    assert data_equivalence(info_1, info_2, exact=True)
    env_1.action_space.seed(SEED)
    for step in range(_steps(grounding)):
        action = masked(env_1, info_1) if step % 2 else env_1.action_space.sample()
        obs_1, rew_1, term_1, trunc_1, info_1 = env_1.step(action)
        obs_2, rew_2, term_2, trunc_2, info_2 = env_2.step(action)
        assert data_equivalence(obs_1, obs_2, exact=True), step
        assert env_1.observation_space.contains(obs_1)
        assert (rew_1, term_1, trunc_1) == (rew_2, term_2, trunc_2), step
        assert data_equivalence(info_1, info_2, exact=True), (step, info_1, info_2)
        if term_1 or trunc_1:
            info_1 = env_1.reset(seed=SEED)[1]
            env_2.reset(seed=SEED)
    env_1.close()
    env_2.close()


@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_pickle_env(env_id: str, grounding: str) -> None:
    """`test_pickle_env`: a pickled env resets and steps as the original."""
    env = make(env_id, grounding, disable_env_checker=True).unwrapped
    action = env.action_space.sample()
    env_reset = env.reset(seed=123)
    env_step = env.step(action)
    pickled = pickle.loads(pickle.dumps(env))
    assert data_equivalence(env_reset, pickled.reset(seed=123))
    assert data_equivalence(env_step, pickled.step(action))
    env.close()
    pickled.close()


# ---------------------------------------------------------------- tests/envs/test_rendering.py
def check_rendered(frame: Any, mode: str) -> None:
    """Gymnasium's `check_rendered` for the modes the kitchen envs declare."""
    if mode == "rgb_array_list":
        assert isinstance(frame, list) and frame
        for f in frame:
            check_rendered(f, "rgb_array")
    else:
        assert isinstance(frame, np.ndarray) and frame.ndim == 3 and frame.shape[2] == 3
        assert frame.dtype == np.uint8 and frame.std() > 5  # a picture, not a blank


@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_render_modes(env_id: str, grounding: str) -> None:
    """`test_render_modes`: every declared mode but "human" renders after reset and step."""
    env = make(env_id, grounding)
    modes = env.metadata["render_modes"]
    assert "rgb_array" in modes
    for mode in modes:
        if mode == "human":
            continue
        new = make(env_id, grounding, render_mode=mode, render_size=(96, 128))
        _, info = new.reset(seed=SEED)
        check_rendered(new.render(), mode)
        new.step(masked(new, info))
        check_rendered(new.render(), mode)
        new.close()
    env.close()


# ---------------------------------------------------------------- actions
@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_out_of_range_and_malformed_actions_raise_value_error(env_id: str, grounding: str) -> None:
    env = make(env_id, grounding).unwrapped
    env.reset(seed=SEED)
    n = int(env.action_space.n)
    malformed = [1.5, np.float32(0.0), "0", None, True, np.array([0, 1])]
    for action in [-1, n, n + 7, np.int64(-3), *malformed]:
        with pytest.raises(ValueError, match="action"):
            env.step(action)
    env.close()


# ---------------------------------------------------------------- tests/vector
@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_vector_envs_async_and_sync_agree(env_id: str, grounding: str) -> None:
    """`test_vector_env_equal`: an async (worker processes) and a sync vector env of the id,
    seeded alike, give equal observations, rewards, flags and info."""
    real, options = variant(env_id, grounding)
    fns = [lambda: make_env(real, grounding=grounding, obs_keys=None, **options)] * 2
    async_env = AsyncVectorEnv(fns, context="spawn")
    sync_env = SyncVectorEnv(fns)
    try:
        obs_a, info_a = async_env.reset(seed=SEED)
        obs_s, info_s = sync_env.reset(seed=SEED)
        assert data_equivalence(obs_a, obs_s, exact=True)
        assert data_equivalence(info_a, info_s, exact=True)
        async_env.action_space.seed(SEED)
        for _ in range(_steps(grounding) // 2):
            actions = async_env.action_space.sample()
            out_a, out_s = async_env.step(actions), sync_env.step(actions)
            for a, s in zip(out_a, out_s, strict=True):
                assert data_equivalence(a, s, exact=True), (a, s)
    finally:
        async_env.close()
        sync_env.close()


# ---------------------------------------------------------------- copies and conventions
def planner_of(env: gym.Env) -> str:
    """The planning method of an env's own domain: utamp2x-rules for the extended domain
    (procedural-v2's labels), else utamp2-gt."""
    return "utamp2x-rules" if env.unwrapped.options.domain == "utamp2x" else "utamp2-gt"


def long_scene(env_id: str, steps: int = 5) -> str:
    """The first scene of the id whose plan has at least `steps` macro actions (so two
    steps in, three more follow)."""
    env = make(env_id, "symbolic").unwrapped
    for scene in env.scenes:
        outcome = plan_scene(scene, planner_of(env))
        if outcome.solved and outcome.plan_length >= steps:
            return scene.name
    raise AssertionError(f"{env_id} has no scene with a plan of {steps} steps")


@pytest.mark.parametrize("env_id", PHYSICS)
def test_pickled_and_deep_copied_physics_envs_step_as_the_original(env_id: str) -> None:
    """After two executed macro actions, a pickled and a deep-copied env give the original's
    next three observations, rewards, failure reasons (and whole info), exactly."""
    real, options = variant(env_id)
    scene = long_scene(env_id)
    env = gym.make(real, scene=scene, disturbance=0.3, pose_noise=0.004, **options)
    obs, info = env.reset(seed=SEED)
    policy = PlannerPolicy(env.unwrapped, method=planner_of(env))
    for _ in range(2):
        obs, _, _, _, info = env.step(policy(obs, info))
        assert info["macro_result"]["executed"]  # the simulator ran
    copies = [pickle.loads(pickle.dumps(env)), copy.deepcopy(env)]
    compared = 0
    for _ in range(3):
        action = policy(obs, info)
        obs, reward, terminated, truncated, info = env.step(action)
        for twin in copies:
            t_obs, t_reward, t_term, t_trunc, t_info = twin.step(action)
            assert data_equivalence(obs, t_obs, exact=True)
            assert (t_reward, t_term, t_trunc) == (reward, terminated, truncated)
            assert t_info["failure_reason"] == info["failure_reason"]
            assert data_equivalence(t_info, info, exact=True)
        compared += 1
        if terminated or truncated:
            break
    assert compared == 3, f"the episode ended {compared} steps after the copy"
    for e in (env, *copies):
        e.close()


def _solvable_seeds(env: gym.Env, n: int) -> list[int]:
    """The first `n` reset seeds whose scene's goal the planner reaches (in the rules)."""
    resets = solvable_resets(env, method=planner_of(env))
    seeds = [seed for seed, *_ in itertools.islice(resets, n)]
    assert len(seeds) == n, f"fewer than {n} solvable scenes in 50 seeds"
    return seeds


def _episode(env: gym.Env, policy: Any, seed: int) -> list[dict[str, Any]]:
    obs, info = env.reset(seed=seed)
    infos = [info]
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        infos.append(info)
        done = terminated or truncated
        assert info["is_success"] == (terminated and reward > 0)
    return infos


@pytest.mark.parametrize(("env_id", "grounding"), CASES)
def test_is_success_on_every_step_and_last(env_id: str, grounding: str) -> None:
    """``info["is_success"]`` (stable-baselines3's key): a bool on reset and every step, True
    on the last step exactly when the goal was reached; episodes that succeed (the planner
    policy) and episodes that do not (random masked actions until the step limit or a dead
    end) both end with it."""
    env = make(env_id, grounding, max_episode_steps=12)
    ends = []
    for seed in _solvable_seeds(env, 2):  # a procedural split also holds unachievable goals
        policy = PlannerPolicy(env.unwrapped, method=planner_of(env))
        infos = _episode(env, policy, seed)
        assert all(type(i["is_success"]) is bool for i in infos)
        ends.append(infos[-1]["is_success"])
    assert any(ends)  # the planner reaches the goal
    env.action_space.seed(SEED)
    infos = _episode(env, lambda obs, info: masked(env, info), SEED)
    assert all(type(i["is_success"]) is bool for i in infos)
    env.close()
