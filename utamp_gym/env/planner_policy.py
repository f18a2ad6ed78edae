"""Deprecated home of `PlannerPolicy`: it moved to `utamp_gym.agents` (policies live there).

Importing a name from here still works for one release, with a `DeprecationWarning`.
"""

from __future__ import annotations

import warnings
from typing import Any

from utamp_gym.agents import planner

_MOVED = ("MAX_BANS", "PLAN_CACHE_SIZE", "PlannerPolicy", "state_problem")


def __getattr__(name: str) -> Any:
    if name in _MOVED:
        warnings.warn(
            f"utamp_gym.env.planner_policy.{name} moved to utamp_gym.agents.{name}; "
            "the old path goes away in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(planner, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
