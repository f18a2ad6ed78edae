"""Closed-loop evaluation: the planner policy acts in the env and replans from what is true.

The paper's protocol is open-loop (plan once, execute, stop at the first failure). Closed
loop (`utamp eval --closed-loop`), `PlannerPolicy` acts in a `UTampKitchenEnv` of the scene:
in physics grounding the env perceives the symbolic state after every step and the policy
replans whenever it differs from the prediction, banning an action that failed from a state
(`utamp_gym.agents.planner`). The world is the ground truth (the env's affordances are
``"gt"``; its domain is the method's, so U-TAMP-1's actions exist); the method only decides
what the policy believes. An episode ends at the goal, at a dead end, when the policy gives
up (`PlanningError`), or after `MAX_STEPS` macro actions.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from utamp_gym.affordances.sources import DEFAULT_NOISE, plan_affordances
from utamp_gym.agents import PlannerPolicy, run_policy
from utamp_gym.agents.episode import Policy
from utamp_gym.backend import DEFAULT_PERCEPTION
from utamp_gym.env.kitchen import DEFAULT_OBJECTS, UTampKitchenEnv
from utamp_gym.env.options import EnvOptions
from utamp_gym.eval.interactive import InteractivePerception
from utamp_gym.methods.perceived import perceive_live
from utamp_gym.methods.perceivers import load_perceiver, split_method
from utamp_gym.planning.methods import method_spec
from utamp_gym.seeding import run_seed
from utamp_gym.suites import SUITES, resolve_scene
from utamp_gym.symbolic.universe import ground_universe

#: macro actions per closed-loop episode (five-object optimal plans have at most 14)
MAX_STEPS = 40
#: the failure of an episode whose scene affords no ground action (nothing to act with)
NO_ACTIONS = "the scene's objects afford no action (every goal is unreachable)"


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
    n_weighings: int = 0  # interactive perception: lifts that weighed an object
    n_looks: int = 0  # interactive perception: extra looks after the first


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
    interactive: bool = True,
) -> ClosedLoopResult:
    """Run `method`'s planner policy on `scene` in the env until the episode ends
    (`perception`: the env option, where the robot's poses come from in physics).
    ``utamp2-perceived[:PERCEIVER]`` looks first and, if `interactive`, measures and revises
    its beliefs as it acts (`utamp_gym.eval.interactive`); else it believes its one look."""
    base, perceiver_spec = split_method(method)
    spec = method_spec(base)
    suite = scene.split("/", 1)[0] if scene.split("/", 1)[0] in SUITES else None
    names = resolve_scene(scene).object_names  # a procedural scene: the universe of its own
    objects = DEFAULT_OBJECTS if set(names) <= set(DEFAULT_OBJECTS) else names
    physics: dict[str, object] = {} if pose_noise is None else {"pose_noise": pose_noise}
    if grounding == "physics":
        physics["perception"] = perception
    where = {"suite": suite, "objects": tuple(objects), "scene": scene, "domain": spec.domain}
    if ground_universe(EnvOptions(**where).universe_key()).n_actions == 0:
        # the scene's own universe affords no action at all (an unachievable procedural
        # scene): no episode can act, and the env's Discrete(0) action space cannot exist
        return ClosedLoopResult(
            success=False, failure=f"no plan from the initial state of {scene}: {NO_ACTIONS}",
            actions=(), n_faults=0, n_replans=0, planning_time_s=0.0, execution_time_s=0.0,
        )  # fmt: skip
    env = UTampKitchenEnv(
        **where,
        grounding=grounding,
        affordances="gt",
        disturbance=disturbance,
        **physics,
    )
    policy = PlannerPolicy(env, base, timeout=timeout, noise=noise, seed=seed)
    world_seed = run_seed(resolve_scene(scene).name, seed)  # the one seed of the episode
    acting: Policy = policy
    interacting = None
    if spec.affordances == "perceived" and interactive:
        perceiver = load_perceiver(perceiver_spec)
        acting = interacting = InteractivePerception(policy, env, perceiver=perceiver)
    elif spec.affordances == "perceived":  # look at the episode's world before the first step
        acting = _LookFirst(policy, env)
    # symbolic: the world a look renders is the one this seed makes in physics (the physics
    # episode draws its world from the env's generator, seeded the same, as measured)
    options = {"world_seed": world_seed} if grounding == "symbolic" else None
    try:
        # the env's reset counts as execution, as in `execute_plan`
        ep = run_policy(env, acting, max_steps=max_steps, seed=world_seed, options=options)
    finally:
        env.close()
    failure = ""
    if ep.ended == "policy":  # the planner gave up: say which physical failure led there
        failure = ep.stopped + (
            f" (last failed step: {ep.last_failure})" if ep.last_failure else ""
        )
    elif ep.ended == "budget":
        failure = f"step budget of {max_steps} macro actions exhausted"
    elif not ep.success:
        failure = _why_ended(ep.info)
    return ClosedLoopResult(
        success=ep.success,
        failure="" if ep.success else failure,
        actions=ep.actions,
        n_faults=ep.n_faults,
        n_replans=policy.n_replans,
        planning_time_s=sum(policy.planning_times),
        execution_time_s=ep.reset_s + ep.step_s,
        n_weighings=0 if interacting is None else interacting.n_weighings,
        n_looks=0 if interacting is None else interacting.n_looks,
    )


class _LookFirst:
    """`utamp2-perceived`'s planner policy: before its first decision it looks at the
    episode's world and believes the affordances perceived there."""

    def __init__(self, policy: PlannerPolicy, env: UTampKitchenEnv) -> None:
        self.policy, self.env = policy, env

    def __call__(self, obs: Any, info: Mapping[str, Any]) -> int:
        if not info.get("action"):
            facts = _perceived_facts(self.env)
            self.policy.believe(self.env.scene.name, facts)
        return self.policy(obs, info)


def _perceived_facts(env: UTampKitchenEnv) -> frozenset:
    """`utamp2-perceived`'s affordances of the env's scene, perceived through its backend's
    cameras (`Surveying`: MuJoCo's, or the symbolic backend's look at the episode's world),
    in the env's names."""
    seen = perceive_live(env.scene, env.backend)
    return seen.usable_facts(plan_affordances(seen.planning))


def _why_ended(info: dict[str, object]) -> str:
    """The reason an episode terminated without reaching the goal."""
    anomalies = {k: v for k, v in dict(info.get("anomalies") or {}).items() if v}
    if anomalies:
        return "no symbol for " + "; ".join(map(str, anomalies.values()))  # type: ignore[attr-defined]
    reason = info.get("failure_reason")
    return f"dead end after {info.get('action')}" + (f": {reason}" if reason else "")
