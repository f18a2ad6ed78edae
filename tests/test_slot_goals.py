"""The goal-conditioned slot policy (`utamp_gym.rl.slots`): goal entries change what it does,
it runs on any slot count, and a model saved before goal conditioning acts as it did.

``data/slot_model_v0/`` was written by its ``make.py`` with the code before goal conditioning
(main at 7ca5dc2): a slot model on UTampKitchenProcedural-v0 and the logits and values that
code gave on four observations.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from sb3_contrib import MaskablePPO

from utamp_gym.env.object_goal import GOAL_KEYS
from utamp_gym.env.objects import n_actions
from utamp_gym.env.registry import register_envs
from utamp_gym.rl.slots import SlotEncoder, SlotPolicy, has_goal

register_envs()
FIXTURE = Path(__file__).resolve().parent / "data" / "slot_model_v0"


def _dist(policy: SlotPolicy, obs: dict[str, np.ndarray], masks: np.ndarray) -> np.ndarray:
    """The masked action distribution's logits (masked-out entries at a large negative)."""
    policy.set_training_mode(False)
    tensor, _ = policy.obs_to_tensor(obs)
    with th.no_grad():
        return policy.get_distribution(tensor, action_masks=masks).distribution.logits.numpy()


def _policy(env: gym.Env, seed: int = 0) -> SlotPolicy:
    th.manual_seed(seed)
    model = MaskablePPO(SlotPolicy, env, seed=seed, device="cpu", n_steps=64, batch_size=64,
                        policy_kwargs={"features_extractor_kwargs": {"d_model": 16},
                                       "head": "pointer"})  # fmt: skip
    with th.no_grad():  # weights away from the near-uniform start, so every input matters
        for p in model.policy.parameters():
            p.add_(0.3 * th.randn_like(p))
    return model.policy


def test_a_model_saved_before_goal_conditioning_acts_as_it_did() -> None:
    cases = np.load(FIXTURE / "cases.npz")
    model = MaskablePPO.load(FIXTURE / "model.zip", device="cpu")
    policy = model.policy
    assert not has_goal(policy.observation_space)
    assert not any(name.startswith("features_extractor.goal") for name in policy.state_dict())
    obs = {k[4:]: cases[k] for k in cases.files if k.startswith("obs_")}
    # the same logits and values up to float rounding (another CPU sums in another order:
    # 1e-6 apart), and the same actions masked out
    logits = _dist(policy, obs, cases["masks"])
    assert np.array_equal(np.isfinite(logits), np.isfinite(cases["logits"]))
    finite = np.isfinite(logits)
    np.testing.assert_allclose(logits[finite], cases["logits"][finite], rtol=1e-5, atol=1e-5)
    tensor, _ = policy.obs_to_tensor(obs)
    with th.no_grad():
        values = policy.predict_values(tensor).numpy()
    np.testing.assert_allclose(values, cases["values"], rtol=1e-5, atol=1e-5)
    # and it still acts on today's env of its id
    env = gym.make("UTampKitchenProcedural-v0", grounding="symbolic", masks="geometric")
    o, info = env.reset(seed=0)
    action, _ = model.predict(o, action_masks=info["action_mask"], deterministic=True)
    assert info["action_mask"][int(action)]


def test_goal_entries_change_the_policys_output() -> None:
    env = gym.make("UTampKitchenGoals-v0", grounding="symbolic", masks="geometric")
    policy = _policy(env)
    assert has_goal(policy.observation_space) and isinstance(policy.features_extractor, SlotEncoder)
    obs, info = env.reset(seed=3)
    batch = {k: v[None] for k, v in obs.items()}
    mask = info["action_mask"][None]
    shown = mask[0]
    rng = np.random.default_rng(0)

    def dist(o: dict[str, np.ndarray]) -> np.ndarray:
        return _dist(policy, o, mask)[0][shown]  # the shown actions' log-probabilities

    base = dist(batch)
    for key in GOAL_KEYS:  # each goal entry, alone, moves the distribution
        changed = {**batch, key: np.zeros_like(batch[key])}
        if not batch[key].any():  # a few literals of this kind (all of them: a constant bias)
            changed[key] = (rng.random(batch[key].shape) < 0.05).astype(batch[key].dtype)
        assert np.abs(dist(changed) - base).max() > 1e-4, key
    # another episode's goal in this episode's state: another distribution
    other = env.reset(seed=4)[0]
    assert any(not np.array_equal(other[k], obs[k]) for k in GOAL_KEYS)
    swapped = {**batch, **{k: other[k][None] for k in GOAL_KEYS}}
    assert np.abs(dist(swapped) - base).max() > 1e-4
    # a goal-free policy of the same state ignores them (it reads only its own entries)
    free = _policy(gym.make("UTampKitchenProcedural-v0", grounding="symbolic", masks="geometric"))
    assert np.array_equal(_dist(free, batch, mask), _dist(free, swapped, mask))


@pytest.mark.parametrize("scene_objects", [3, 8])
def test_an_eight_slot_policy_acts_on_small_and_large_scenes(scene_objects: int) -> None:
    split = "procedural-v2/test-count" if scene_objects == 8 else "procedural-v2/train"
    env = gym.make("UTampKitchenGoals-v0", grounding="symbolic", split=split, slots=8,
                   num_objects=scene_objects)  # fmt: skip
    policy = _policy(env)
    obs, info = env.reset(seed=0)
    assert obs["present"].sum() == scene_objects and obs["present"].shape == (8,)
    logits = _dist(policy, {k: v[None] for k, v in obs.items()}, info["action_mask"][None])
    assert logits.shape == (1, n_actions(8))
    assert np.isfinite(logits[0][info["action_mask"]]).all()
    action, _ = policy.predict(obs, action_masks=info["action_mask"], deterministic=True)
    assert info["action_mask"][int(action)]
    env.step(int(action))
