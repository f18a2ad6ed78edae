"""Closed-loop evaluation: the planner policy acts in the env and replans from what is true.

The paper's protocol is open-loop (plan once, execute, stop at the first failure). Closed
loop (`utamp eval --closed-loop`), `PlannerPolicy` acts in a `UTampKitchenEnv` of the scene:
in physics grounding the env perceives the symbolic state after every step and the policy
replans whenever it differs from the prediction, banning an action that failed from a state
(`utamp_gym.env.planner_policy`). The world is the ground truth (the env's affordances are
``"gt"``; its domain is the method's, so U-TAMP-1's actions exist); the method only decides
what the policy believes. An episode ends at the goal, at a dead end, when the policy gives
up (`PlanningError`), or after `MAX_STEPS` macro actions.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from utamp_gym.affordances.sources import DEFAULT_NOISE
from utamp_gym.backend import DEFAULT_PERCEPTION
from utamp_gym.env.kitchen import DEFAULT_OBJECTS, UTampKitchenEnv
from utamp_gym.env.planner_policy import PlannerPolicy
from utamp_gym.errors import PlanningError
from utamp_gym.planning.methods import method_spec
from utamp_gym.seeding import run_seed
from utamp_gym.suites import SUITES, resolve_scene

#: macro actions per closed-loop episode (five-object optimal plans have at most 14)
MAX_STEPS = 40


@dataclass(frozen=True)
class ClosedLoopResult:
    """One closed-loop episode: outcome, what was executed and how often it replanned."""

    success: bool
    failure: str
    actions: tuple[str, ...]
    n_faults: int
    n_replans: int
    planning_time_s: float
    execution_time_s: float


def run_closed_loop(
    scene: str,
    method: str = "utamp2-gt",
    *,
    seed: int = 0,
    grounding: str = "physics",
    disturbance: float = 0.0,
    pose_noise: float | None = None,
    noise: float = DEFAULT_NOISE,
    timeout: float = 30.0,
    max_steps: int = MAX_STEPS,
    perception: str = DEFAULT_PERCEPTION,
) -> ClosedLoopResult:
    """Run `method`'s planner policy on `scene` in the env until the episode ends
    (`perception`: the env option, where the robot's poses come from in physics)."""
    spec = method_spec(method)
    suite = scene.split("/", 1)[0] if scene.split("/", 1)[0] in SUITES else None
    names = resolve_scene(scene).object_names  # a procedural scene: the universe of its own
    objects = DEFAULT_OBJECTS if set(names) <= set(DEFAULT_OBJECTS) else names
    physics: dict[str, object] = {} if pose_noise is None else {"pose_noise": pose_noise}
    if grounding == "physics":
        physics["perception"] = perception
    env = UTampKitchenEnv(
        suite=suite,
        objects=objects,
        scene=scene,
        grounding=grounding,
        domain=spec.domain,
        affordances="gt",
        disturbance=disturbance,
        **physics,
    )
    policy = PlannerPolicy(env, method, timeout=timeout, noise=noise, seed=seed)
    actions: list[str] = []
    n_faults, failure, success = 0, "", False
    execution = 0.0
    try:
        start = time.perf_counter()
        # counted as execution, as in `execute_plan`; seeded per (scene, seed) as it is
        obs, info = env.reset(seed=run_seed(resolve_scene(scene).name, seed))
        execution += time.perf_counter() - start
        if spec.affordances == "perceived":  # look at the episode's world first
            policy.believe(env.scene.name, _perceived_facts(env, seed))
        for _ in range(max_steps):
            try:
                action = policy(obs, info)
            except PlanningError as exc:
                failure = str(exc)
                break
            start = time.perf_counter()
            obs, reward, terminated, truncated, info = env.step(action)
            execution += time.perf_counter() - start
            actions.append(str(info["action"]))
            n_faults += bool(info["fault"])
            if terminated or truncated:
                success = reward > 0
                if not success:
                    failure = _why_ended(info)
                break
        else:
            failure = f"step budget of {max_steps} macro actions exhausted"
    finally:
        env.close()
    planning = sum(policy.planning_times)
    return ClosedLoopResult(
        success=success,
        failure="" if success else failure,
        actions=tuple(actions),
        n_faults=n_faults,
        n_replans=policy.n_replans,
        planning_time_s=planning,
        execution_time_s=execution,
    )


def _perceived_facts(env: UTampKitchenEnv, seed: int) -> frozenset:
    """`utamp2-perceived`'s affordances of the env's scene, perceived in its world (physics)
    or in the episode's world built for a look (symbolic), in the env's names."""
    from utamp_gym.affordances.sources import plan_affordances
    from utamp_gym.methods.perceived import perceive_live, perceive_scene

    seen = (
        perceive_scene(env.scene, seed)
        if env.backend is None
        else perceive_live(env.scene, env.backend)
    )
    return seen.usable_facts(plan_affordances(seen.planning))


def _why_ended(info: dict[str, object]) -> str:
    """The reason an episode terminated without reaching the goal."""
    anomalies = {k: v for k, v in dict(info.get("anomalies") or {}).items() if v}
    if anomalies:
        return "no symbol for " + "; ".join(map(str, anomalies.values()))  # type: ignore[attr-defined]
    reason = info.get("failure_reason")
    return f"dead end after {info.get('action')}" + (f": {reason}" if reason else "")
