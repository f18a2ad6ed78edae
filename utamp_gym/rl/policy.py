"""Trained RL agents as ``policy(obs, info) -> action`` and the episode loop that scores them.

Why: the evaluation harness treats every method (planner, RL agent) alike, as a callable on
the env's observation and info. `RLPolicy` feeds the model only the observation entries it
was trained on and, by default, restricts its choice to the applicable actions
(``info["action_mask"]``, else the env's `action_masks()`) by masking the logits (PPO,
MaskablePPO) or Q-values (DQN), so masks help at inference even an agent trained without.
`run_episodes` is the loop behind `evaluate_rl`; it accepts any such callable (e.g.
`PlannerPolicy`).
"""

from __future__ import annotations

import json
import time
import zipfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from utamp_gym.env.registry import register_envs
from utamp_gym.env.task import GOAL_REWARD
from utamp_gym.rl.saved import ModelError, read_meta, trained_entries

if TYPE_CHECKING:
    from utamp_gym.rl.saved import ModelMeta

ALGOS = ("maskable-ppo", "ppo", "dqn")
Policy = Callable[[Mapping[str, np.ndarray], Mapping[str, Any] | None], int]


def algo_of(path: str | Path) -> str:
    """Which of `ALGOS` saved the SB3 zip at `path` (from its `ModelMeta`, else its policy
    class)."""
    try:
        return read_meta(path).algo
    except ModelError:
        pass  # no metadata (saved by SB3 directly or by an older version)
    try:
        with zipfile.ZipFile(path) as z:
            data = json.loads(z.read("data"))
    except (OSError, KeyError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a stable-baselines3 model zip ({exc})") from exc
    module = str(data.get("policy_class", {}).get("__module__", ""))
    algo = data.get("policy_class", {}).get("utamp_algo")  # utamp_gym.rl.policies classes
    if algo in ALGOS:
        return str(algo)
    if module.startswith("sb3_contrib.common.maskable"):
        return "maskable-ppo"
    if module.startswith("stable_baselines3.dqn"):
        return "dqn"
    if module.startswith(("stable_baselines3.common.policies", "stable_baselines3.ppo")):
        return "ppo"
    raise ValueError(f"{path}: policy class from '{module}' is not one of {', '.join(ALGOS)}")


def algo_class(algo: str) -> type:
    """The SB3 / sb3-contrib class of an algorithm name."""
    if algo == "maskable-ppo":
        from sb3_contrib import MaskablePPO

        return MaskablePPO
    if algo == "ppo":
        from stable_baselines3 import PPO

        return PPO
    if algo == "dqn":
        from stable_baselines3 import DQN

        return DQN
    raise ValueError(f"unknown algo {algo!r}; valid: {', '.join(ALGOS)}")


class RLPolicy:
    """``policy(obs, info) -> action id`` around a MaskablePPO, PPO or DQN model.

    `obs` is the env's full observation (entries the model was not trained on are dropped).
    With ``masks=True`` the action is the best *applicable* one (invalid logits or Q-values
    set to −inf, as MaskablePPO does), the mask taken from ``info["action_mask"]`` or, without
    it, from `env` (its `action_masks()`); an all-false mask (a dead end) falls back to the
    unmasked choice. ``deterministic=False`` samples the (masked) PPO distribution from a
    generator seeded with `seed`; DQN stays greedy.
    """

    def __init__(
        self,
        model: Any,
        *,
        env: gym.Env | None = None,
        masks: bool = True,
        deterministic: bool = True,
        seed: int = 0,
    ) -> None:
        self.model, self.env, self.masks, self.deterministic = model, env, masks, deterministic
        self.meta: ModelMeta | None = None  # the saved env options, set by `load_rl_policy`
        self.keys = tuple(model.observation_space.spaces)
        self.algo = _algo_of_model(model)
        self._rng = np.random.default_rng(seed)

    def reset(self) -> None:
        """Nothing to forget between episodes (the policy is memoryless)."""

    def __call__(self, obs: Mapping[str, np.ndarray], info: Mapping[str, Any] | None = None) -> int:
        entries = trained_entries(self.keys, obs)
        scores = self._scores({k: np.asarray(v) for k, v in entries.items()})
        mask = self._mask(info)
        if mask is not None:
            scores = np.where(mask, scores, -np.inf)
        if self.deterministic or self.algo == "dqn":
            return int(np.argmax(scores))
        p = np.exp(scores - scores.max())
        return int(self._rng.choice(len(p), p=p / p.sum()))

    def _mask(self, info: Mapping[str, Any] | None) -> np.ndarray | None:
        if not self.masks:
            return None
        if info is not None and "action_mask" in info:
            mask = np.asarray(info["action_mask"], bool)
        elif self.env is not None:
            mask = np.asarray(self.env.unwrapped.action_masks(), bool)  # type: ignore[attr-defined]
        else:
            raise ValueError("masks=True needs info['action_mask'] or an env")
        return mask if mask.any() else None

    def _scores(self, x: dict[str, np.ndarray]) -> np.ndarray:
        """The unmasked action logits (PPO, MaskablePPO) or Q-values (DQN)."""
        import torch

        policy = self.model.policy
        with torch.no_grad():
            tensor, _ = policy.obs_to_tensor(x)
            if self.algo == "dqn":
                out = policy.q_net(tensor)
            else:
                out = policy.get_distribution(tensor).distribution.logits
        return out[0].cpu().numpy().astype(np.float64)


def _algo_of_model(model: Any) -> str:
    module = type(model).__module__
    if module.startswith("sb3_contrib"):
        return "maskable-ppo"
    return "dqn" if type(model).__name__ == "DQN" else "ppo"


def load_rl_policy(
    path: str | Path,
    *,
    env: gym.Env | None = None,
    masks: bool = True,
    deterministic: bool = True,
    seed: int = 0,
) -> RLPolicy:
    """Load a model zip saved by `utamp_gym.rl.train` (algorithm detected from the zip); its
    `ModelMeta` (None for zips without it) becomes the policy's `meta`."""
    import torch

    torch.set_num_threads(1)
    model = algo_class(algo_of(path)).load(str(path), device="cpu")
    policy = RLPolicy(model, env=env, masks=masks, deterministic=deterministic, seed=seed)
    try:
        policy.meta = read_meta(path)
    except ModelError:
        policy.meta = None
    return policy


def run_episodes(
    env: gym.Env, policy: Policy, episodes: Iterable[tuple[str, int]]
) -> list[dict[str, Any]]:
    """One row per (scene, seed): ``reset(seed=seed, options={"scene": scene})``, then act.

    Success is reaching the goal (a terminal step paying the goal reward, shaping aside);
    `invalid_actions` counts actions outside the mask, `failed_actions` every step with a
    ``failure_reason`` (invalid ones and, in physics grounding, physical failures).
    """
    kitchen = env.unwrapped
    rows = []
    for scene, seed in episodes:
        reset = getattr(policy, "reset", None)
        if callable(reset):
            reset()
        start = time.perf_counter()
        obs, info = env.reset(seed=int(seed), options={"scene": scene})
        steps = invalid = failed = 0
        success = done = False
        while not done:
            action = policy(obs, info)
            invalid += not bool(info["action_mask"][action])
            obs, reward, terminated, truncated, info = env.step(action)
            steps += 1
            failed += bool(info["failure_reason"])
            done = terminated or truncated
            success = bool(terminated and float(reward) >= GOAL_REWARD)
        rows.append({
            "scene": scene,
            "n_objects": int(kitchen.scene.n_objects),  # type: ignore[attr-defined]
            "seed": int(seed),
            "success": success,
            "steps": steps,
            "invalid_actions": invalid,
            "failed_actions": failed,
            "episode_time_s": time.perf_counter() - start,
        })  # fmt: skip
    return rows


def evaluate_rl(
    path: str | Path | RLPolicy,
    env_id: str | None = None,
    *,
    scenes: Sequence[str] | None = None,
    num_objects: int | None = None,
    seeds: Iterable[int] = (0,),
    grounding: str = "symbolic",
    masks: bool = True,
    env_kwargs: Mapping[str, Any] | None = None,
) -> list[dict[str, Any]]:
    """Episodes of a trained agent: one row per (scene, seed) (see `run_episodes`).

    `scenes` defaults to every scene of the env (with `num_objects` objects if given). Rows
    hold ``scene, n_objects, seed, success, steps, invalid_actions, failed_actions,
    episode_time_s``; the env is built without reward shaping or termination on failure.
    The env id and options (``masks``) default to the model's saved ones (`ModelMeta`).
    """
    register_envs()  # explicitly: a worker process may have skipped it on import

    policy = path if isinstance(path, RLPolicy) else load_rl_policy(path, masks=masks)
    meta = policy.meta
    env_id = env_id or (meta.env_id if meta is not None else "UTampKitchen-v0")
    kwargs = {
        "reward_shaping": False,
        "terminate_on_failure": False,
        **(meta.env_kwargs if meta is not None else {}),
        **(env_kwargs or {}),
    }
    env = gym.make(env_id, grounding=grounding, num_objects=num_objects, **kwargs)
    try:
        all_scenes = env.unwrapped.scenes  # type: ignore[attr-defined]
        names = list(scenes) if scenes is not None else [s.name for s in all_scenes]
        seed_list = list(seeds)
        return run_episodes(env, policy, [(n, s) for n in names for s in seed_list])
    finally:
        env.close()
