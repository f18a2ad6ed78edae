"""Deprecated home of `PlannerPolicy`: it moved to `utamp_gym.agents` (policies live there).

Importing a name from here still works for one release, with a `DeprecationWarning`.
"""

from utamp_gym.moved import moved

__getattr__ = moved(
    __name__, "utamp_gym.agents", ("MAX_BANS", "PLAN_CACHE_SIZE", "PlannerPolicy", "state_problem")
)
