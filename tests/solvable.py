"""Resets whose scene's goal is achievable: a procedural split also holds scenes whose goal
is not (planners report those unsolvable), and a planner-policy test needs one it can reach."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import gymnasium as gym


def solvable_resets(
    env: gym.Env, start: int = 0, tries: int = 50
) -> Iterator[tuple[int, Any, dict[str, Any]]]:
    """(seed, obs, info) of each ``reset(seed=s)``, s from `start` on (`tries` seeds), whose
    scene's goal UTAMP-2 with ground-truth affordances reaches."""
    from utamp_gym.planning.methods import plan_scene

    for s in range(start, start + tries):
        obs, info = env.reset(seed=s)
        if plan_scene(env.unwrapped.scene, "utamp2-gt").solved:
            yield s, obs, info
