"""`run_policy`: the one episode loop, a policy acting in a kitchen env through ``env.step``.

Why one loop: the closed-loop planner (`utamp_gym.eval.closed_loop`), a saved RL agent
(`utamp_gym.rl.harness`) and a plan played open loop (`OpenLoopPolicy`) are episodes of the
same env; success, the failure reason of a step, faults and timings are the env's
(``info["is_success"]``, ``info["failure_reason"]``, ``info["fault"]``), counted here once.

A policy is ``policy(obs, info) -> action``; it ends the episode early by raising
`PlanningError` (a planner with no plan, an open-loop plan that failed or ran out). The loop
ends at termination or truncation, when the policy stops, or after `max_steps` actions.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from utamp_gym.errors import PlanningError

#: why an episode ended: the env terminated it (goal, dead end, anomaly, failure with
#: ``terminate_on_failure``), truncated it, the policy stopped, or the step budget ran out
ENDINGS = ("terminated", "truncated", "policy", "budget")

Policy = Callable[[Any, Mapping[str, Any]], Any]
#: called after every step with (action, obs, reward, terminated, truncated, info)
StepHook = Callable[[Any, Any, float, bool, bool, Mapping[str, Any]], None]


@dataclass(frozen=True)
class Episode:
    """One episode: what was done, how it ended and where the time went (s)."""

    success: bool  # the env's last info["is_success"]
    ended: str  # one of ENDINGS
    stopped: str  # the policy's reason when ended == "policy", else ""
    actions: tuple[str, ...]  # info["action"] of every step (failed ones too)
    n_failed: int  # steps with a failure reason
    last_failure: str  # the last step's failure reason that was not ""
    n_faults: int  # injected faults (physics grounding with disturbance)
    reset_s: float
    decision_s: float  # inside the policy
    step_s: float  # inside env.step
    info: Mapping[str, Any]  # the last info (of the reset if no step was taken)
    #: per step: info["action"], the info and the env's `macro_result` (None: not executed)
    records: tuple[tuple[str, Mapping[str, Any], Any], ...] = ()
    first: tuple[Any, Mapping[str, Any]] | None = None  # the reset's observation and info


def run_policy(
    env: gym.Env[Any, Any],
    policy: Policy,
    *,
    max_steps: int,
    seed: int | None = None,
    options: Mapping[str, Any] | None = None,
    through_termination: bool = False,
    on_step: StepHook | None = None,
) -> Episode:
    """Reset `env` (`seed`, `options`) and let `policy` act until the episode ends
    (`through_termination`: only when the policy stops or the budget runs out, e.g. an
    open-loop plan, played to its end whatever the env perceives); `on_step` sees every
    step (e.g. a dataset recorder); the reset's observation and info are the returned
    episode's `first`."""
    start = time.perf_counter()
    obs, info = env.reset(seed=seed, options=dict(options) if options else None)
    first = (obs, info)
    reset_s = time.perf_counter() - start
    actions: list[str] = []
    records: list[tuple[str, Mapping[str, Any], Any]] = []
    kitchen = env.unwrapped
    n_failed = n_faults = 0
    last_failure, stopped, ended = "", "", "budget"
    decision = stepping = 0.0
    for _ in range(max_steps):
        t0 = time.perf_counter()
        try:
            action = policy(obs, info)
        except PlanningError as exc:
            decision += time.perf_counter() - t0
            ended, stopped = "policy", str(exc)
            break
        t1 = time.perf_counter()
        obs, reward, terminated, truncated, info = env.step(action)
        decision, stepping = decision + t1 - t0, stepping + time.perf_counter() - t1
        if on_step is not None:
            on_step(action, obs, float(reward), bool(terminated), bool(truncated), info)
        actions.append(str(info["action"]))
        records.append((actions[-1], info, getattr(kitchen, "macro_result", None)))
        n_faults += bool(info.get("fault"))
        if info["failure_reason"]:
            n_failed, last_failure = n_failed + 1, str(info["failure_reason"])
        if (terminated or truncated) and not through_termination:
            ended = "terminated" if terminated else "truncated"
            break
    return Episode(
        success=bool(info["is_success"]),
        ended=ended,
        stopped=stopped,
        actions=tuple(actions),
        n_failed=n_failed,
        last_failure=last_failure,
        n_faults=n_faults,
        reset_s=reset_s,
        decision_s=decision,
        step_s=stepping,
        info=info,
        records=tuple(records),
        first=first,
    )
