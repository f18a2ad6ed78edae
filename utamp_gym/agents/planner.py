"""`PlannerPolicy`: Fast Downward as a closed-loop policy for the kitchen envs.

Why: a planning baseline must act in the same env as learned agents. The policy plans from the
*current* symbolic state (the ``symbolic`` observation plus the env's static atoms, written
out as a PDDL problem; in physics grounding both are perceived from the simulator), follows
the plan, and replans whenever the observed state is not the one the plan predicted (a failed
action, a physical surprise, a new episode, or an exhausted plan).

It never loops: an action that failed (``info["failure_reason"]``) from a state is banned from
that state for the rest of the episode, and the next plan from it avoids the banned actions;
after `MAX_BANS` different failures from one state it gives up with a `PlanningError` naming
that state. Plans are cached per (scene, state, static atoms, bans), so replanning from a
state seen before costs nothing. Every planner call's wall time (problem writing, grounding
and search) is appended to `planning_times`; `n_replans` counts the plans made this episode
after its first.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.sources import DEFAULT_NOISE, affordances_for
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.physics import perceived_static
from utamp_gym.errors import PlanningError, UnknownNameError
from utamp_gym.planning.fast_downward import DEFAULT_SEARCH, SEARCH_CONFIGS
from utamp_gym.planning.methods import method_spec
from utamp_gym.planning.state_planner import StatePlanner
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.atoms import scene_atoms
from utamp_gym.symbolic.pddl import parse_domain
from utamp_gym.symbolic.problem import domain_text, problem_goal
from utamp_gym.symbolic.scene_cache import SceneCache


def state_problem(
    scene: Scene,
    objects: Iterable[str],
    atoms: Iterable[str],
    domain: str,
    name: str = "now",
    goal: Sequence[str] | None = None,
) -> str:
    """PDDL problem text: the scene's objects, the given init atoms and the goal literals
    `goal` (default: the scene's goal, else the paper's tower: `problem_goal`)."""
    pname = "utamp-" + scene.name.replace("/", "-") + f"-{name}"
    lines = [f"(define (problem {pname})", f"  (:domain {domain})", "  (:objects"]
    lines.append("    " + " ".join(objects) + " - obj)")
    lines.append("  (:init")
    lines.extend(f"    {a}" for a in sorted(atoms))
    lines += ["  )", "  (:goal (and"]
    lines.extend(f"    {g}" for g in (problem_goal(scene) if goal is None else goal))
    lines += ["  ))", ")"]
    return "\n".join(lines) + "\n"


#: different failed actions from one state after which the policy gives up
MAX_BANS = 3
#: plans with steps outside the env's action space after which the policy gives up
MAX_OUTSIDE = 8
#: plans kept in the per-state cache
PLAN_CACHE_SIZE = 4096
_State = tuple[str, int, frozenset[str]]  # scene, fluent bits, static atoms


class PlannerPolicy:
    """``policy(obs, info) -> action id`` for a (possibly wrapped) `UTampKitchenEnv`, in its
    action space (with ``interface="objects"``: the object-centric index of each plan step).

    `method` is a planning method of `utamp_gym.planning.methods` (domain + affordance
    source); if it matches the env's own domain and affordances, the planner sees exactly the
    env's static atoms (including this episode's noisy detection); otherwise it plans with its
    own affordances, and a mismatch shows up as failed actions and replanning (e.g. a ground-
    truth planner in a noisy env). Raises `PlanningError` if
    no plan exists from the current state (or the planner times out), or if a plan step is
    not in the env's action space.
    """

    def __init__(
        self,
        env: gym.Env[Any, Any],
        method: str = "utamp2-gt",
        *,
        search: str = DEFAULT_SEARCH,
        timeout: float = 30.0,
        noise: float = DEFAULT_NOISE,
        seed: int = 0,
    ) -> None:
        kitchen = env.unwrapped
        if not isinstance(kitchen, UTampKitchenEnv):
            raise ValueError(f"PlannerPolicy needs a UTampKitchenEnv, got {kitchen!r}")
        if search not in SEARCH_CONFIGS:
            raise UnknownNameError("search configuration", search, SEARCH_CONFIGS)
        if not timeout > 0:
            raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
        self.env = kitchen
        self.spec = method_spec(method)
        self.search, self.timeout, self.noise = search, timeout, noise
        self.planning_times: list[float] = []
        self.plans: list[tuple[str, ...]] = []
        self._domain_text = domain_text(self.spec.domain)
        domain = parse_domain(self._domain_text, source=f"{self.spec.domain}.pddl")
        self._fluent = domain.fluent_predicates()
        self._rng = np.random.default_rng(seed)
        self._facts: dict[str, frozenset[Fact]] = {}
        self._cache: OrderedDict[tuple[_State, frozenset[int]], tuple[int, ...]] = OrderedDict()
        self.n_replans = 0
        self.bans: dict[_State, set[int]] = {}
        self._plan: list[int] = []
        self._expected: int | None = None
        self._last: tuple[_State, int] | None = None

    def believe(self, scene: str, facts: Iterable[Fact]) -> None:
        """Plan scene `scene` with these affordance facts (e.g. perceived ones) instead of
        the method's own source (a change of belief drops the current plan: the next
        decision replans)."""
        facts = frozenset(facts)
        if self._facts.get(scene) != facts:
            self._plan = []
        self._facts[scene] = facts

    def reset(self) -> None:
        """Start a new episode: forget the plan, the bans and the replan count."""
        self._plan, self._expected, self._last = [], None, None
        self.bans, self.n_replans = {}, 0

    def __call__(self, obs: Mapping[str, np.ndarray], info: Mapping[str, Any] | None = None) -> int:
        universe = self.env.universe
        if info is not None and not info.get("action"):  # the first step of an episode
            self.reset()
        objects = self.env.objects
        if objects is None:
            bits = sum(1 << int(j) for j in np.flatnonzero(obs["symbolic"]))
        else:  # object-centric observations: the env's own symbolic state
            index = universe.fluent_index
            bits = universe.state_bits(a for a in self.env.true_atoms() if a in index)
        state = (self.env.scene.name, bits, self.env.static_atoms)
        if self._last is not None and info is not None and info.get("failure_reason"):
            before, failed = self._last
            self.bans.setdefault(before, set()).add(failed)
        if bits != self._expected or not self._plan or self._plan[0] in self.bans.get(state, ()):
            if self._expected is not None:
                self.n_replans += 1
            self._plan = list(self._plan_from(state))
        action = self._plan.pop(0)
        self._expected = universe.successor(bits, action)
        self._last = (state, action)
        if objects is not None:
            index_of = objects.index_of(action)
            if index_of < 0:
                raise PlanningError(
                    f"plan step {universe.actions[action]} has no object-centric action"
                )
            return index_of
        return action

    # ------------------------------------------------------------------ internals
    def _static_atoms(self, scene: Scene) -> frozenset[str]:
        opts = self.env.options
        own = "none" if opts.domain == "utamp1" else opts.affordances
        mine = "none" if self.spec.domain == "utamp1" else self.spec.affordances
        if (opts.domain, own) == (self.spec.domain, mine) and scene.name not in self._facts:
            return self.env.static_atoms
        if scene.name not in self._facts:
            self._facts[scene.name] = affordances_for(
                scene, self.spec.affordances, self._rng, self.noise, self.spec.domain
            )[0]
        facts = self._facts[scene.name]
        static = scene_atoms(scene, facts, self.spec.domain, self._fluent)[0]
        perception = self.env.perception  # physics: orientation atoms as perceived
        return static if perception is None else perceived_static(static, perception)

    def _plan_from(self, state: _State) -> tuple[int, ...]:
        """A plan from `state` avoiding its banned actions (cached), or `PlanningError`."""
        banned = frozenset(self.bans.get(state, ()))
        universe = self.env.universe
        if len(banned) >= MAX_BANS:
            failed = ", ".join(sorted(universe.actions[a] for a in banned))
            raise PlanningError(
                f"giving up on {state[0]}: {len(banned)} actions failed from the same state "
                f"({failed}); state: {' '.join(universe.atoms_of(state[1]))}"
            )
        key = (state, banned)
        plan = self._cache.get(key)
        if plan is None:
            plan = self._replan(state[1], frozenset(universe.actions[a] for a in banned))
            self._cache[key] = plan
            if len(self._cache) > PLAN_CACHE_SIZE:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(key)
        return plan

    def _replan(self, bits: int, exclude: frozenset[str]) -> tuple[int, ...]:
        """A plan from state `bits` without the `exclude` steps, in the env's action space:
        a step the env cannot take (a method planning with other affordances than the env's,
        e.g. perceived ones) is left out and the planner asked again, `MAX_OUTSIDE` times."""
        universe = self.env.universe
        outside: set[str] = set()
        for _ in range(MAX_OUTSIDE + 1):
            steps = self._plan_steps(bits, exclude | outside)
            ids: list[int] = []
            for step in steps:
                try:
                    ids.append(universe.index(step))
                except UnknownNameError:
                    outside.add(step)
            if len(ids) == len(steps):
                self.plans.append(steps)
                return tuple(ids)
        shown = ", ".join(f"'{step}'" for step in sorted(outside)[:3])
        raise PlanningError(
            f"every plan has a step not in the env's action space ({len(outside)} left out, "
            f"e.g. {shown}; replanned {MAX_OUTSIDE} times; method {self.spec.name} vs env "
            f"domain {self.env.options.domain})"
        )

    def _plan_steps(self, bits: int, exclude: frozenset[str]) -> tuple[str, ...]:
        """One plan (PDDL steps) from state `bits` without the `exclude` steps."""
        env, universe = self.env, self.env.universe
        scene = env.scene
        start = time.perf_counter()
        # one StatePlanner per policy, created on first use: replans of an episode (and of
        # every episode of the same scene) re-use its grounded task; objects kept per scene
        if getattr(self, "_state_planner", None) is None:
            self._state_planner = StatePlanner(
                self.spec.domain, search=self.search, timeout=self.timeout
            )
            self._scene_objects: SceneCache[tuple[str, ...]] = SceneCache()
        objects = self._scene_objects.get(
            scene.name, lambda: scene_atoms(scene, (), self.spec.domain, self._fluent)[2]
        )
        result = self._state_planner.plan(
            objects,
            self._static_atoms(scene),
            universe.atoms_of(bits),
            env.goal.literals,  # the episode's goal (the env option ``task``)
            exclude=exclude,
        )
        self.planning_times.append(time.perf_counter() - start)
        if not result.solved:
            avoiding = f" avoiding {', '.join(sorted(exclude))}" if exclude else ""
            raise PlanningError(
                f"no plan from the current state of {scene.name}{avoiding}: {result.reason}"
            )
        if not result.plan:
            raise PlanningError(f"the goal of {scene.name} already holds: nothing to do")
        return result.plan
