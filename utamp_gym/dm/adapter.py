"""`DmEnvAdapter`: a Gymnasium kitchen env as a `dm_env.Environment`.

Why: dm_control-style agents (Acme, ...) consume `TimeStep`s and specs. The adapter maps
``reset`` to a FIRST step, ``terminated`` to a LAST step with discount 0, ``truncated`` (the
step limit) to a LAST step with discount 1, and auto-resets on the next `step`, as dm_env
requires. Observations are the Gym ``Dict`` entries plus ``action_mask`` (dm_env has no
info), so masked agents need nothing else.
"""

from __future__ import annotations

from typing import Any

import dm_env
import gymnasium as gym
import numpy as np
from dm_env import specs
from gymnasium import spaces


def space_to_spec(space: spaces.Space, name: str) -> specs.Array:
    """The dm_env spec of a Box or MultiBinary Gymnasium space."""
    if isinstance(space, spaces.Box):
        return specs.BoundedArray(space.shape, space.dtype, space.low, space.high, name)
    if isinstance(space, spaces.MultiBinary):
        return specs.BoundedArray(space.shape, space.dtype, 0, 1, name)
    raise ValueError(f"no dm_env spec for observation entry '{name}' of type {type(space)}")


class DmEnvAdapter(dm_env.Environment):
    """Wraps a Gym env with a ``Dict`` observation space and a ``Discrete`` action space.

    `seed` seeds the first reset (later episodes continue the env's RNG stream).
    """

    def __init__(self, env: gym.Env[Any, Any], seed: int | None = None) -> None:
        if not isinstance(env.observation_space, spaces.Dict):
            raise ValueError(f"expected a Dict observation space, got {env.observation_space}")
        if not isinstance(env.action_space, spaces.Discrete):
            raise ValueError(f"expected a Discrete action space, got {env.action_space}")
        self.env = env
        self._seed = seed
        self._needs_reset = True
        self._n = int(env.action_space.n)
        self._obs_spec = {k: space_to_spec(s, k) for k, s in env.observation_space.spaces.items()}
        self._obs_spec["action_mask"] = specs.Array((self._n,), bool, "action_mask")

    def _observation(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> dict[str, Any]:
        return {**obs, "action_mask": np.asarray(info["action_mask"], bool)}

    def reset(self) -> dm_env.TimeStep:
        obs, info = self.env.reset(seed=self._seed)
        self._seed = None
        self._needs_reset = False
        return dm_env.restart(self._observation(obs, info))

    def step(self, action: Any) -> dm_env.TimeStep:
        if self._needs_reset:
            return self.reset()
        obs, reward, terminated, truncated, info = self.env.step(np.int64(action))
        observation = self._observation(obs, info)
        reward = np.float64(reward)
        if terminated or truncated:
            self._needs_reset = True
            end = dm_env.termination if terminated else dm_env.truncation
            return end(reward, observation)
        return dm_env.transition(reward, observation)

    def observation_spec(self) -> dict[str, specs.Array]:
        return dict(self._obs_spec)

    def action_spec(self) -> specs.DiscreteArray:
        return specs.DiscreteArray(self._n, dtype=np.int64, name="action")

    def reward_spec(self) -> specs.Array:
        return specs.Array((), np.float64, "reward")

    def discount_spec(self) -> specs.BoundedArray:
        return specs.BoundedArray((), np.float64, 0.0, 1.0, "discount")

    def close(self) -> None:
        self.env.close()
