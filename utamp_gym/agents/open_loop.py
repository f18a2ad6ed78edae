"""`OpenLoopPolicy`: a plan made once, played step by step, stopped at its first failure.

Why: the paper's protocol is open loop (plan once, execute, stop at the first failed step);
as a policy it runs in the same env loop (`run_policy`) as every other agent, so the env
decides success, failure reasons and faults.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym

from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.errors import PlanningError, UnknownNameError


class PlanStopped(PlanningError):
    """The open-loop plan failed at a step or has no step left."""


class OpenLoopPolicy:
    """``policy(obs, info) -> action id`` playing `plan` (PDDL strings) in order in `env`'s
    action space (objects interface: each step's object-centric index). A step not in the
    env's action space raises `PlanningError` at construction."""

    def __init__(self, env: gym.Env[Any, Any], plan: Sequence[str]) -> None:
        kitchen = env.unwrapped
        if not isinstance(kitchen, UTampKitchenEnv):
            raise ValueError(f"OpenLoopPolicy needs a UTampKitchenEnv, got {kitchen!r}")
        self.env, self.plan = kitchen, tuple(plan)
        try:
            self._ids = [kitchen.universe.index(step) for step in self.plan]
        except UnknownNameError as exc:
            raise PlanningError(
                f"plan step '{exc.name}' is not in the env's action space"
            ) from None
        self._next = 0

    def reset(self) -> None:
        self._next = 0

    def __call__(self, obs: Any, info: Mapping[str, Any]) -> int:
        if not info.get("action"):  # the first step of an episode
            self.reset()
        elif info.get("failure_reason"):
            i = self._next - 1
            raise PlanStopped(f"step {i} {self.plan[i]}: {info['failure_reason']}")
        if self._next >= len(self._ids):
            raise PlanStopped(f"plan of {len(self._ids)} steps played")
        a = self._ids[self._next]
        self._next += 1
        objects = self.env.objects
        if objects is None:
            return a
        index = objects.index_of(a)
        if index < 0:
            raise PlanningError(
                f"plan step {self.plan[self._next - 1]} has no object-centric action"
            )
        return index
