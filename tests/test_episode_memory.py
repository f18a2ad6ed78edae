"""An episode's simulation is freed as soon as the next reset replaces it.

Nothing of an episode may sit in a reference cycle: the world (MuJoCo model and data, collision
models) would then live until Python's next full garbage collection, several episodes later,
and a long run's memory would swing by hundreds of MB of C heap between collections
(`benchmarks/memory.py` measures the long run; this checks the cause on one reset).
"""

from __future__ import annotations

import gc
import weakref

import gymnasium as gym

from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.registry import register_envs

register_envs()


def test_the_previous_episode_is_freed_by_the_reset_without_the_garbage_collector() -> None:
    env = gym.make("UTampKitchen-v0")
    policy = PlannerPolicy(env.unwrapped)
    obs, info = env.reset(seed=3)
    gc.collect()
    gc.disable()  # what a reference cycle keeps now stays until the end of the test
    try:
        for _ in range(2):  # a pick and a place: IK lines, OMPL, the held object's collision
            obs, _, _, _, info = env.step(policy(obs, info))
            assert info["macro_result"]["success"], info["failure_reason"]
        state = env.unwrapped.backend.state
        refs = {"state": weakref.ref(state), "arm": weakref.ref(state.arm)}
        del state
        env.reset(seed=4)
        alive = [name for name, ref in refs.items() if ref() is not None]
    finally:
        gc.enable()
    env.close()
    assert not alive, f"the previous episode's {alive} outlived the reset (a reference cycle)"
