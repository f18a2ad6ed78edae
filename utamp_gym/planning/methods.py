"""Planning methods of the paper's experiments: where affordances come from + which domain.

* ``utamp2-gt``    – U-TAMP-2 with the hand-written ground-truth affordances
* ``utamp2-rules`` – U-TAMP-2 with affordances parsed from the true attributes
* ``utamp2-noisy`` – U-TAMP-2 with affordances parsed from noisily detected attributes
                     (the offline stand-in for the paper's VLM detector)
* ``utamp2-perceived`` – U-TAMP-2 with affordances parsed from attributes perceived in
                     rendered RGB-D views (`utamp_gym.methods.perceived` looks at the scene
                     and plans its *planning scene*, whose types are the perceived ones)
* ``utamp1``       – the original U-TAMP domain, no affordances
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, NamedTuple

import utamp_gym.affordances.sources as _sources
from utamp_gym.affordances.facts import Fact, Scores
from utamp_gym.affordances.sources import DEFAULT_NOISE, affordances_for, detection_rng
from utamp_gym.deadline import Deadline
from utamp_gym.errors import PlanningTimeout, UnknownNameError
from utamp_gym.moved import forward
from utamp_gym.planning.downward import DEFAULT_SEARCH
from utamp_gym.planning.state_planner import StatePlanner
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.problem import build_problem, domain_text
from utamp_gym.tasks.goal import Goal

if TYPE_CHECKING:  # numpy, the rule parser and the noisy detector load only when used
    import numpy as np

METHODS = (
    "utamp2-gt", "utamp2-rules", "utamp2-noisy", "utamp2-perceived", "utamp1",
    "utamp2x-gt", "utamp2x-rules",
)  # fmt: skip


class MethodSpec(NamedTuple):
    name: str
    domain: str
    affordances: str  # gt | rules | noisy | perceived


#: the affordance sourcing moved to `utamp_gym.affordances.sources`: its other names
#: (`ground_truth_for`, `scene_types`, ...) still import from here, with a warning
__getattr__, _ = forward(__name__, _sources)

SPECS = {
    "utamp2-gt": MethodSpec("utamp2-gt", "utamp2", "gt"),
    "utamp2-rules": MethodSpec("utamp2-rules", "utamp2", "rules"),
    "utamp2-noisy": MethodSpec("utamp2-noisy", "utamp2", "noisy"),
    "utamp2-perceived": MethodSpec("utamp2-perceived", "utamp2", "perceived"),
    "utamp1": MethodSpec("utamp1", "utamp1", "gt"),
    # the extended domain: rim pinches granted (`utamp_gym.affordances.rim`)
    "utamp2x-gt": MethodSpec("utamp2x-gt", "utamp2x", "gt"),
    "utamp2x-rules": MethodSpec("utamp2x-rules", "utamp2x", "rules"),
}


def method_spec(method: str) -> MethodSpec:
    if method not in SPECS:
        raise UnknownNameError("method", method, METHODS)
    return SPECS[method]


class PlanOutcome(NamedTuple):
    """The result of planning one scene with one method (what `utamp plan --json` prints)."""

    scene: str
    method: str
    n_objects: int
    solved: bool
    plan: tuple[str, ...]
    planning_time_s: float
    reason: str | None
    seed: int
    affordance_scores: Scores
    domain: str = ""
    problem: str = ""
    facts: frozenset[Fact] = frozenset()
    timed_out: bool = False
    phase: str | None = None  # the phase that ran out of time (`utamp_gym.deadline.PHASES`)

    @property
    def plan_length(self) -> int:
        return len(self.plan)

    def __repr__(self) -> str:  # without the long `domain`, `problem` and `facts`
        hidden = ("domain", "problem", "facts")
        shown = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields if n not in hidden)
        return f"PlanOutcome({shown})"

    def to_json(self) -> dict[str, Any]:
        """The JSON object; the affordance scores are None (null) for a method without
        affordances (utamp1)."""
        spec = SPECS.get(self.method)
        s = None if spec is not None and spec.domain == "utamp1" else self.affordance_scores
        return {
            "scene": self.scene,
            "method": self.method,
            "n_objects": self.n_objects,
            "seed": self.seed,
            "solved": self.solved,
            "plan": list(self.plan),
            "plan_length": self.plan_length,
            "planning_time_s": round(self.planning_time_s, 6),
            "reason": self.reason,
            "timed_out": self.timed_out,
            "phase": self.phase,
            "affordance_precision": None if s is None else round(s.precision, 4),
            "affordance_recall": None if s is None else round(s.recall, 4),
            "affordance_f1": None if s is None else round(s.f1, 4),
        }


def plan_scene(
    scene: Scene,
    method: str = "utamp2-gt",
    *,
    seed: int = 0,
    timeout: float = 30.0,
    search: str | None = None,
    noise: float = DEFAULT_NOISE,
    rng: np.random.Generator | None = None,
    planner: StatePlanner | None = None,
    deadline: Deadline | None = None,
    affordances: tuple[frozenset[Fact], Scores] | None = None,
    goal: Goal | None = None,
) -> PlanOutcome:
    """Abstract the scene, plan with Fast Downward, and report.

    The planning time covers affordance detection, problem generation, grounding, SAS
    writing and search; `timeout` bounds all of it, or `deadline` if given (e.g. one that
    started before the scene was loaded). Without `rng`, noisy detection draws from
    `detection_rng(seed, scene.name)`. `planner` (a `StatePlanner` of the method's domain)
    re-uses its cached groundings; `search` defaults to its configuration, else
    `DEFAULT_SEARCH`. An unsolvable task or a time-out comes back with ``solved=False`` and
    a reason (a time-out also with the phase that ran out of time). `affordances` (facts and
    their scores) replaces the method's own source: ``utamp2-perceived`` plans the declared
    scene with the facts perceived in it (`utamp_gym.methods.perceived.plan_perceived`).
    `goal` replaces the scene's goal (its own, else the paper's tower: `build_problem`).
    """
    spec = method_spec(method)
    start = time.perf_counter()
    if deadline is None:
        deadline = Deadline.after(timeout, start)
    if planner is None:
        planner = StatePlanner(spec.domain, search=search or DEFAULT_SEARCH, timeout=timeout)
    elif planner.domain.name != spec.domain or (search is not None and search != planner.search):
        raise ValueError(
            f"planner plans {planner.domain.name} with {planner.search}; method {method} "
            f"needs {spec.domain}" + (f" with {search}" if search else "")
        )
    if rng is None and spec.affordances == "noisy":
        rng = detection_rng(seed, scene.name)
    timed_out, phase = False, None
    late = deadline.expired()  # already out of time when called: the caller's phase
    if affordances is None:
        facts, scores = affordances_for(scene, spec.affordances, rng, noise, spec.domain)
    else:
        facts, scores = affordances
    domain = domain_text(spec.domain)
    problem = build_problem(scene, facts, spec.domain, goal)
    fluent = planner.domain.fluent_predicates()
    static, state = [], []
    for text in problem.init:
        atom = text.lower()
        (state if atom[1 : atom.find(" ")] in fluent else static).append(atom)
    try:
        deadline.check("scene" if late else "problem")
        result = planner.plan(
            problem.objects, static, state, [g.lower() for g in problem.goal], deadline=deadline
        )
        solved, plan, reason = result.solved, result.plan, result.reason
    except PlanningTimeout as exc:
        solved, plan, reason, timed_out = False, (), f"planner timed out: {exc}", True
        phase = exc.phase
    elapsed = time.perf_counter() - start
    return PlanOutcome(
        scene=scene.name,
        method=method,
        n_objects=scene.n_objects,
        solved=solved,
        plan=plan,
        planning_time_s=elapsed,
        reason=reason,
        seed=seed,
        affordance_scores=scores,
        domain=domain,
        problem=problem.text,
        facts=facts,
        timed_out=timed_out,
        phase=phase,
    )
