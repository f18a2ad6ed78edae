"""The macro track: planner-policy episodes of a kitchen env, step by step.

An episode is ``env.reset(seed=s)`` (the env's RNG picks the scene) followed by the planner
policy's actions (`utamp_gym.agents.PlannerPolicy`: Fast Downward, replanning from
the observed state) until the goal, a dead end, the time limit or a planner error. Each step
keeps the observation, the action id, the reward, termination and truncation, and the env's
info (its fixed structure: the macro action's PDDL string, the action mask, the failure reason,
...: `utamp_gym.env.info`). Timings are not recorded, so equal seeds give identical episodes.

Every episode regenerates from its metadata: ``gym.make(env_id, **env_options)``, then
``reset(seed=seed)`` and the stored actions (`replay`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from utamp_gym.agents import PlannerPolicy, run_policy
from utamp_gym.data.minari_io import Episode
from utamp_gym.env.registry import register_envs
from utamp_gym.scene.io import scene_to_toml

#: a bound on an episode's steps beyond the env's own time limit (which ends it first)
MAX_STEPS = 100_000
#: env options of a recorded episode besides the grounding (fixed: infos must be reproducible)
RECORDED = {"record_timings": False}


@dataclass(frozen=True)
class MacroTask:
    """One episode to record (picklable: sent to worker processes or Ray)."""

    env_id: str
    index: int
    seed: int
    method: str = "utamp2-gt"
    env_options: Mapping[str, Any] = field(default_factory=dict)


def make_env(env_id: str, env_options: Mapping[str, Any]) -> Any:
    import gymnasium as gym

    register_envs()
    return gym.make(env_id, **{**env_options, **RECORDED})


def record_episode(task: MacroTask) -> Episode:
    """Run the planner policy for one episode of `task` (the one loop, `run_policy`; the
    env's time limit ends it) and keep every step."""
    env = make_env(task.env_id, task.env_options)
    try:
        policy = PlannerPolicy(env, method=task.method)
        steps: list[tuple[Any, ...]] = []
        run = run_policy(
            env, policy, max_steps=MAX_STEPS, seed=task.seed,
            on_step=lambda *step: steps.append(step),
        )  # fmt: skip
        assert run.first is not None
        ep = Episode(seed=task.seed, observations=[run.first[0]], infos=[run.first[1]])
        for action, obs, reward, terminated, truncated, info in steps:
            ep.observations.append(obs)
            ep.actions.append(int(action))
            ep.rewards.append(reward)
            ep.terminations.append(terminated)
            ep.truncations.append(truncated)
            ep.infos.append(info)
        error = run.stopped
        if error and ep.actions:  # the planner gave up: the episode ends here
            ep.truncations[-1] = True
        scene = env.unwrapped.scene
        ep.metadata = {
            "index": task.index,
            "scene": scene.name,
            "scene_file": scene_to_toml(scene),
            "seed": task.seed,
            "env_id": task.env_id,
            "env_options": dict(task.env_options),
            "method": task.method,
            "macro_actions": [str(i["action"]) for i in ep.infos[1:]],
            "success": run.success if ep.actions else False,
            "planner_error": error,
        }
        return ep
    finally:
        env.close()


def tasks(
    env_id: str, episodes: int, *, seed: int = 0, method: str = "utamp2-gt",
    env_options: Mapping[str, Any] | None = None,
) -> list[MacroTask]:  # fmt: skip
    """`episodes` tasks, with the reset seeds ``seed`` to ``seed + episodes - 1``."""
    opts = dict(env_options or {})
    return [MacroTask(env_id, i, seed + i, method, opts) for i in range(episodes)]


def replay(env_id: str, env_options: Mapping[str, Any], seed: int, actions: Sequence[int]) -> Any:
    """The last observation after ``reset(seed=seed)`` and `actions` (an episode, again)."""
    env = make_env(env_id, env_options)
    try:
        obs, _ = env.reset(seed=int(seed))
        for a in actions:
            obs = env.step(int(a))[0]
        return obs
    finally:
        env.close()


def same_observation(a: Mapping[str, np.ndarray], b: Mapping[str, np.ndarray]) -> bool:
    """Whether two (dict) observations are equal entry by entry."""
    return set(a) == set(b) and all(np.array_equal(a[k], b[k]) for k in a)
