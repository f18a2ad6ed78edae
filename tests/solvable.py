"""Resets whose scene's goal is achievable: a procedural split also holds scenes whose goal
is not (planners report those unsolvable), and a planner-policy test needs one it can reach."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import gymnasium as gym


def solvable_resets(
    env: gym.Env, start: int = 0, tries: int = 50, method: str = "utamp2-gt"
) -> Iterator[tuple[int, Any, dict[str, Any]]]:
    """(seed, obs, info) of each ``reset(seed=s)``, s from `start` on (`tries` seeds), whose
    scene's goal planning `method` (default: UTAMP-2 with ground-truth affordances) reaches."""
    from utamp_gym.planning.methods import plan_scene

    for s in range(start, start + tries):
        obs, info = env.reset(seed=s)
        if plan_scene(env.unwrapped.scene, method).solved:
            yield s, obs, info
