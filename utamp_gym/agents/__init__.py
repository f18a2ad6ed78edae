"""Policies that act in the kitchen envs through ``env.step``: `PlannerPolicy` (Fast
Downward, replanning from the observed state), `OpenLoopPolicy` (a plan made once, stopped at
its first failure) and `run_policy`, the one episode loop every evaluation uses."""

from utamp_gym.agents.episode import Episode, run_policy
from utamp_gym.agents.open_loop import OpenLoopPolicy, PlanStopped
from utamp_gym.agents.planner import MAX_BANS, PLAN_CACHE_SIZE, PlannerPolicy, state_problem

__all__ = [
    "MAX_BANS",
    "PLAN_CACHE_SIZE",
    "Episode",
    "OpenLoopPolicy",
    "PlanStopped",
    "PlannerPolicy",
    "run_policy",
    "state_problem",
]
