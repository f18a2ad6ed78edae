"""SB3 policy classes that read only the observation entries they were trained on.

Why: the agents train on ``symbolic`` + ``present`` (`utamp_gym.rl.envs`), but the env's raw
observation has more entries (``object_poses``, ``robot``, ...), and SB3's ``predict`` fails
on a Dict with keys outside the policy's observation space (``KeyError: 'object_poses'``). The
observation filter therefore travels with the model: these subclasses of SB3's multi-input
policies drop the extra entries before anything else, so ``model.predict(obs)`` works on
``gym.make(...)``'s raw observation. SB3 saves the policy class by reference, so a model
trained with them loads (and filters) wherever `utamp_gym` is installed.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from sb3_contrib.common.maskable.policies import MaskableMultiInputActorCriticPolicy
from stable_baselines3.common.policies import MultiInputActorCriticPolicy
from stable_baselines3.dqn.policies import MultiInputPolicy as DQNMultiInputPolicy

from utamp_gym.rl.distributions import use_fast_masked
from utamp_gym.rl.saved import trained_entries


class _TrainedKeys:
    """Mixin: keep only the Dict entries of the policy's observation space (`trained_entries`:
    a clear error for an observation of the other env interface)."""

    observation_space: Any

    def obs_to_tensor(self, observation: Any) -> Any:
        if isinstance(observation, Mapping):
            observation = trained_entries(tuple(self.observation_space.spaces), observation)
        return super().obs_to_tensor(observation)  # type: ignore[misc]


class MaskableKeysPolicy(_TrainedKeys, MaskableMultiInputActorCriticPolicy):
    """MaskablePPO's multi-input policy on the trained observation entries only."""

    utamp_algo = "maskable-ppo"  # SB3 writes class attributes into the zip's "data"

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        use_fast_masked(self)  # the same distribution, normalised without a slow path


class KeysActorCriticPolicy(_TrainedKeys, MultiInputActorCriticPolicy):
    """PPO's multi-input policy on the trained observation entries only."""

    utamp_algo = "ppo"


class KeysDQNPolicy(_TrainedKeys, DQNMultiInputPolicy):
    """DQN's multi-input policy on the trained observation entries only."""

    utamp_algo = "dqn"


#: the policy class each algorithm trains with
POLICY_CLASSES: Mapping[str, type] = MappingProxyType(
    {"maskable-ppo": MaskableKeysPolicy, "ppo": KeysActorCriticPolicy, "dqn": KeysDQNPolicy}
)
