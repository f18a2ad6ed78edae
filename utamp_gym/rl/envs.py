"""Training and evaluation envs for the RL baselines: one factory, so both see the same env.

Why: an agent trained on one observation layout must be evaluated on the same one. Every
RL env is ``gym.make(env_id, grounding=..., ...)`` with its observation reduced to
`DEFAULT_OBS_KEYS` (``symbolic`` + ``present``): in symbolic grounding those determine the
task (poses follow the symbolic state, the robot stays home), and in physics grounding they
are the same symbolic quantities, so a policy trained symbolically acts unchanged on the
simulator. Masks come from the env's own `action_masks()` (sb3-contrib finds it through the
wrappers with ``get_wrapper_attr``), so no `ActionMasker` is needed.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import FilterObservation

from utamp_gym.env.registry import env_definitions, register_envs

#: observation entries the RL agents see (None in `make_env` keeps them all)
DEFAULT_OBS_KEYS = ("symbolic", "present")
#: the entries of the objects interface (`utamp_gym.env.objects.observation_space`)
OBJECT_OBS_KEYS = (
    "present", "attributes", "poses", "up", "regions", "spaces", "held", "contact", "free",
    "in_workspace", "member_in_workspace", "grasp",
)  # fmt: skip
#: offset of the evaluation seeds from the training seed (distinct RNG streams)
EVAL_SEED_OFFSET = 10_000


def default_interface(env_id: str, algo: str = "maskable-ppo") -> str:
    """The interface `utamp_gym.rl.train.train` uses unless told: the env's own (its
    ``interface`` option, as ``gym.make`` has it: ``objects`` for UTampKitchenProcedural-v0),
    except ``grounded`` for PPO and DQN, which the objects interface cannot train."""
    own = next((d.kwargs.get("interface") for d in env_definitions() if d.id == env_id), None)
    if algo not in ("maskable-ppo", "bc"):
        return "grounded"
    return str(own or "grounded")


def env_option(env_id: str, name: str, options: dict[str, Any] | None = None) -> Any:
    """The value option `name` has on ``gym.make(env_id, **options)``: `options`' own, else
    the env file's default (None if neither sets it)."""
    if options and name in options:
        return options[name]
    return next((d.kwargs.get(name) for d in env_definitions() if d.id == env_id), None)


def make_env(
    env_id: str = "UTampKitchen-v0",
    *,
    grounding: str = "symbolic",
    num_objects: int | None = None,
    obs_keys: Sequence[str] | None = DEFAULT_OBS_KEYS,
    monitor: bool = False,
    **kwargs: Any,
) -> gym.Env:
    """``gym.make(env_id, ...)`` reduced to `obs_keys`, optionally in an SB3 ``Monitor``."""
    # explicitly: `import utamp_gym` registers nothing in a worker of the `utamp` process
    # (its argv is the command's), e.g. SubprocVecEnv's for `utamp train --grounding physics`
    register_envs()
    env = gym.make(env_id, grounding=grounding, num_objects=num_objects, **kwargs)
    if obs_keys is not None:
        env = FilterObservation(env, list(obs_keys))
    if monitor:
        from stable_baselines3.common.monitor import Monitor

        env = Monitor(env)
    return env


def _copied(x: Any) -> Any:
    """`x` with its arrays, dicts and lists copied (what ``deepcopy`` of an info would give:
    nothing else in an info is mutable)."""
    if isinstance(x, np.ndarray):
        return x.copy()
    if isinstance(x, dict):
        return {k: _copied(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_copied(v) for v in x]
    return x


class _Infos(list):  # type: ignore[type-arg]
    """The info buffer of `_DummyVecEnv`: ``deepcopy`` of it copies only what can change."""

    def __deepcopy__(self, memo: dict[int, Any]) -> list[Any]:
        return [_copied(info) for info in self]


def _dummy_vec_env(fns: list[Callable[[], gym.Env]]) -> Any:
    """SB3's ``DummyVecEnv``, without the generic ``deepcopy`` of every step's observations and
    infos (a seventh of a symbolic objects-interface step): the same copies, made directly."""
    from stable_baselines3.common.vec_env import DummyVecEnv
    from stable_baselines3.common.vec_env.util import dict_to_obs

    class _DummyVecEnv(DummyVecEnv):
        def __init__(self, env_fns: list[Callable[[], gym.Env]]) -> None:
            super().__init__(env_fns)
            self.buf_infos = _Infos(self.buf_infos)

        def _obs_from_buf(self) -> Any:
            return dict_to_obs(self.observation_space, _copied(dict(self.buf_obs)))

    return _DummyVecEnv(fns)


def make_vec_env(
    env_id: str,
    n_envs: int,
    *,
    seed: int = 0,
    subproc: bool = False,
    **kwargs: Any,
) -> Any:
    """`n_envs` monitored copies of `make_env` in a ``DummyVecEnv`` (or ``SubprocVecEnv``).

    The symbolic env steps at >20k/s, so in-process vectorisation is the fast choice there;
    subprocesses only pay off when each step is a physics simulation.
    """
    from stable_baselines3.common.vec_env import SubprocVecEnv

    fns: list[Callable[[], gym.Env]] = [
        functools.partial(make_env, env_id, monitor=True, **kwargs) for _ in range(n_envs)
    ]
    vec = SubprocVecEnv(fns, start_method="spawn") if subproc else _dummy_vec_env(fns)
    vec.seed(seed)
    return vec


def n_fluents(env: Any) -> int:
    """Entries of the ``symbolic`` observation (0 for the objects interface, which has none)."""
    space = env.observation_space
    return int(space["symbolic"].n) if "symbolic" in space.spaces else 0
