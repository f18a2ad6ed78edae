"""Atoms of a scene's initial state and the affordance facts a universe is grounded from.

Atoms are lower-case PDDL text, as `symbolic.pddl` normalises names, so text from the problem
generator (``isP2PSupportive``) and from the parser (``isp2psupportive``) compare equal.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.rules import FINGER_PAIRS, PALM_PARTS
from utamp_gym.affordances.sources import affordances_for, scene_types
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import SIDES
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.pddl import Atom, Domain
from utamp_gym.symbolic.problem import build_problem, instantiate_affordances, problem_goal
from utamp_gym.symbolic.scene_cache import SceneCache
from utamp_gym.tasks.goal import Goal, split_literal


def parse_atom(text: str) -> Atom:
    """``"(oc in hand air)"`` -> Atom('oc', ('in', 'hand', 'air')), lower-cased like the parser."""
    parts = text.strip().strip("()").lower().split()
    return Atom(parts[0], tuple(parts[1:]))


def possible_affordances(types: Iterable[ObjectType]) -> frozenset[Fact]:
    """Every fact the rule parser could derive from *any* corruption of these types' attributes.

    Noisy detection only corrupts shapes, food flags, mass, robustness and member sizes; it
    keeps movability, member names, the palm parts and the finger pairs the rules consider.
    So this is a superset of every noisy detection, used to ground the noisy universe.
    """
    types = list(types)
    movable = [t for t in types if t.movable]
    facts: set[Fact] = set()
    for t in types:
        for part in SIDES if t.movable else ("on",):
            facts.add(("isSupportive", t.name, part))
    for t in movable:
        for part in SIDES:
            facts.add(("isSupportable", t.name, part))
        for member in t.members:
            facts.add(("canLift", t.name, member))
            for palm in PALM_PARTS:
                for f1, f2 in FINGER_PAIRS:
                    facts.add(("canGraspFrom", t.name, member, palm, f1, f2))
        for t2 in types:
            if t2.name == t.name:
                continue
            for p2 in SIDES if t2.movable else ("on",):
                for p1 in SIDES:
                    facts.add(("isP2PSupportive", p2, t2.name, p1, t.name))
                    if not t2.movable:
                        facts.add(("canSlide", t.name, t2.name, p1, p2))
    return frozenset(facts)


def scene_atoms(
    scene: Scene, facts: Iterable[Fact], domain_name: str, fluent: frozenset[str]
) -> tuple[frozenset[str], frozenset[str], tuple[str, ...]]:
    """(static, fluent, objects) of a scene's initial state, atoms as lower-case PDDL.

    `fluent`: the domain's fluent predicates (`Domain.fluent_predicates()`).
    """
    problem = build_problem(scene, facts, domain_name)
    static_atoms, fluent_atoms = set(), set()
    for text in problem.init:
        atom = parse_atom(text)
        (fluent_atoms if atom.predicate in fluent else static_atoms).add(str(atom))
    return frozenset(static_atoms), frozenset(fluent_atoms), problem.objects


def universe_facts(scene: Scene, affordances: str, domain: str = "utamp2") -> frozenset[Fact]:
    """The affordance facts a scene contributes to the universe of an affordance source."""
    if affordances == "none":
        return frozenset()
    rng = np.random.default_rng(0)  # unused by "gt" and "rules"
    if affordances == "noisy":
        gt = affordances_for(scene, "gt", rng, domain=domain)[0]
        return possible_affordances(scene_types(scene)) | gt
    return affordances_for(scene, affordances, rng, domain=domain)[0]


def goal_sides(literals: Iterable[str]) -> tuple[frozenset[str], frozenset[str]]:
    """(atoms that must hold, atoms that must not) of goal literals, normalised like
    `parse_atom` (``"(not (oc under mug pan))"`` -> the second set)."""
    yes: set[str] = set()
    no: set[str] = set()
    for lit in literals:
        positive, body = split_literal(lit.lower())
        (yes if positive else no).add(str(parse_atom(body)))
    return frozenset(yes), frozenset(no)


@dataclass(frozen=True)
class EpisodeAtoms:
    """A scene's initial state for one episode: static, fluent and goal atoms (lower-case);
    `goal` must hold, `goal_negative` must not (the goal's negated literals)."""

    static: frozenset[str]
    fluent: frozenset[str]
    goal: frozenset[str]
    goal_negative: frozenset[str] = frozenset()


class InitialAtoms:
    """Initial atoms of scenes under one (domain, affordance source), cached per scene.

    Why a cache: `build_problem` takes about a millisecond, and resets should be cheap. With
    noisy affordances the affordance atoms are re-detected on every call (from `rng`); the
    rest of the scene's atoms are still cached.
    """

    def __init__(self, domain: Domain, domain_name: str, affordances: str, noise: float) -> None:
        self.fluent, self.domain_name = domain.fluent_predicates(), domain_name
        self.noisy = affordances == "noisy" and domain_name != "utamp1"
        self.source = "gt" if affordances == "noisy" else affordances  # utamp1: unused
        self.noise = noise
        self._cache: SceneCache[EpisodeAtoms] = SceneCache()

    def __call__(
        self, scene: Scene, rng: np.random.Generator, goal: Goal | None = None
    ) -> EpisodeAtoms:
        """The episode's atoms; the goal is `goal`'s literals, else the scene's goal, else the
        paper's tower (`problem_goal`). Cached per scene (`Scene.key`): a caller passes the same
        `goal` for a scene every time."""

        def derive() -> EpisodeAtoms:
            facts = (  # no draws
                ()
                if self.noisy
                else affordances_for(scene, self.source, rng, domain=self.domain_name)[0]
            )
            static, fluent, _ = scene_atoms(scene, facts, self.domain_name, self.fluent)
            yes, no = goal_sides(problem_goal(scene, goal))
            return EpisodeAtoms(static, fluent, yes, no)

        cached = self._cache.get(scene.key, derive)
        if not self.noisy:
            return cached
        facts = affordances_for(scene, "noisy", rng, self.noise)[0]
        detected = {str(parse_atom(a)) for a in instantiate_affordances(scene, facts)}
        return EpisodeAtoms(
            cached.static | detected, cached.fluent, cached.goal, cached.goal_negative
        )
