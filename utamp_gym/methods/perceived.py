"""`utamp2-perceived`: look at the scene with the cameras, plan with the perceived attributes.

The perceiver (`utamp_gym.perception.objects`) only gets the rendered views. This module,
in the evaluation layer, may read the scene, and does what needs both:

* `perceive_scene` resets the physics backend to the episode's world (the same seed gives
  the same initial poses and colours as the physics run), takes the survey look, perceives
  every object and writes each as its own catalogue type (``<object>-seen``) in the object's
  declared orientation; the rule parser (`affordances.rules`) turns these perceived types
  (the *planning scene*'s) into affordance facts;
* `align_members` pairs each perceived member with a declared one by box overlap (the
  perceiver names members by kind and side, the catalogue by its own convention): the
  perceived facts are renamed through it, for scoring against the ground truth and for
  planning the declared scene (`plan_perceived`: its initial state is the scene's, as for
  `utamp2-noisy`); a perceived member with no declared counterpart keeps its name (its
  facts are false positives, and have no symbol to plan with);
* `attribute_accuracy` compares every perceived attribute with the declared one
  (`ATTRIBUTES`), per object, for the eval rows.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from utamp_gym.affordances.facts import Fact, Scores, score
from utamp_gym.affordances.sources import SEEN_SUFFIX, ground_truth_for, plan_affordances
from utamp_gym.agents.runs import episode_result, open_loop_env
from utamp_gym.backend import DEFAULT_BACKEND, DEFAULT_POSE_NOISE, backend_factory
from utamp_gym.contract.perceiver import PerceivedAttributes, Perceiver, PerceptionRequest
from utamp_gym.errors import UtampError
from utamp_gym.methods.attributes import ATTRIBUTES
from utamp_gym.methods.doubt import DOUBT_THRESHOLD, DoubtfulPlan, cautious_types, hoped_facts
from utamp_gym.methods.perceivers import PERCEIVED, BuiltinPerceiver
from utamp_gym.perception.confidence import mass_class
from utamp_gym.planning.methods import PlanOutcome, plan_scene
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import SIDES, Box
from utamp_gym.scene.model import Scene
from utamp_gym.seeding import run_seed

#: what each ``acc_<attribute>`` column measures (`attribute_accuracy`):
#: body (box or cylinder), members (Dice of the matched members), member_size (matched boxes
#: within SIZE_TOL in every extent), shape (the six part shapes), surface (usable sizes of
#: on / under within SIZE_TOL), height (their heights within HEIGHT_TOL), food (food-surface
#: flags), material, mass (within a factor MASS_FACTOR), mass_class (the class between the
#: rules' mass thresholds, `perception.confidence.MASS_BOUNDS`: how the rules read a mass),
#: robustness
SIZE_TOL = 0.01  # m
HEIGHT_TOL = 0.005  # m
MASS_FACTOR = 1.5
MIN_OVERLAP = 0.1  # IoU below which two member boxes are not the same member


def seen_type_name(obj: str) -> str:
    return obj + SEEN_SUFFIX


def _iou(a: Box, b: Box) -> float:
    lo = np.maximum(a.min, b.min)
    hi = np.minimum(a.max, b.max)
    inter = float(np.prod(np.clip(hi - lo, 0.0, None)))
    union = float(np.prod(a.size)) + float(np.prod(b.size)) - inter
    return inter / union if union > 0 else 0.0


def align_members(perceived: ObjectType, declared: ObjectType) -> dict[str, str]:
    """Perceived member name -> declared member name (bodies pair; the others greedily by
    box overlap, at least `MIN_OVERLAP`, preferring the same kind)."""
    out = {perceived.body.name: declared.body.name}
    pairs = []
    for pn, pm in perceived.members.items():
        if pm.kind == "body":
            continue
        for dn, dm in declared.members.items():
            if dm.kind == "body":
                continue
            iou = _iou(pm.box, dm.box)
            if iou >= MIN_OVERLAP:
                pairs.append((iou + (1.0 if pm.kind == dm.kind else 0.0), pn, dn))
    used: set[str] = set()
    for _, pn, dn in sorted(pairs, reverse=True):
        if pn not in out and dn not in used:
            out[pn] = dn
            used.add(dn)
    return out


def rename_fact(
    fact: Fact, types: Mapping[str, str], members: Mapping[str, Mapping[str, str]]
) -> Fact:
    """A fact over perceived types in declared names (unmatched members keep theirs)."""
    pred = fact[0]
    if pred == "isP2PSupportive":
        return (pred, fact[1], types.get(fact[2], fact[2]), fact[3], types.get(fact[4], fact[4]))
    if pred in ("canSlide", "canSlideEdge"):
        return (pred, types.get(fact[1], fact[1]), types.get(fact[2], fact[2]), *fact[3:])
    t = fact[1]
    if pred in ("canGraspFrom", "canLift", "canEdgePinch"):
        member = members.get(t, {}).get(fact[2], "?" + fact[2])
        return (pred, types.get(t, t), member, *fact[3:])
    return (pred, types.get(t, t), *fact[2:])


@dataclass(frozen=True)
class PerceivedScene:
    """A perceived scene: the planning scene, and how it maps onto the declared one."""

    declared: Scene
    planning: Scene
    types: Mapping[str, ObjectType]  # object -> perceived type (its own name)
    members: Mapping[str, Mapping[str, str]]  # object -> perceived member -> declared member
    accuracy: Mapping[str, float]  # attribute -> mean accuracy over the objects
    perceive_s: float = 0.0
    #: object -> what the perceiver reported (confidences, alternatives); empty: certain
    reports: Mapping[str, PerceivedAttributes] = field(default_factory=dict)
    doubt: DoubtfulPlan = field(default_factory=DoubtfulPlan)  # how doubt was planned

    def declared_facts(self, facts: Iterable[Fact]) -> frozenset[Fact]:
        """Facts over the perceived types, in the declared types' and members' names."""
        types = {seen_type_name(o.name): o.type for o in self.declared.objects}
        members = {seen_type_name(o): m for o, m in self.members.items()}
        return frozenset(rename_fact(f, types, members) for f in facts)

    def usable_facts(self, facts: Iterable[Fact]) -> frozenset[Fact]:
        """`declared_facts` without those on members the declared types do not have (the
        declared world has no symbol for them: a planner in it cannot use them)."""
        return frozenset(
            f for f in self.declared_facts(facts) if not any(a.startswith("?") for a in f)
        )

    def scores(self, facts: Iterable[Fact], truth: Iterable[Fact]) -> Scores:
        return score(self.declared_facts(facts), truth)


def attribute_accuracy(
    perceived: ObjectType, declared: ObjectType, members: Mapping[str, str]
) -> dict[str, float]:
    """Accuracy of each attribute in `ATTRIBUTES` for one object (fractions in [0, 1])."""
    out: dict[str, float] = {}
    out["body"] = float(perceived.body.geom == declared.body.geom)
    matched = [p for p in members if p != perceived.body.name]
    n_p = len(perceived.members) - 1
    n_d = len(declared.members) - 1
    out["members"] = 1.0 if n_p == n_d == 0 else 2 * len(matched) / (n_p + n_d)
    boxes = [(perceived.members[p].box, declared.members[d].box) for p, d in members.items()]
    out["member_size"] = float(
        np.mean([np.all(np.abs(a.size - b.size) <= SIZE_TOL) for a, b in boxes])
    )
    out["shape"] = float(
        np.mean([perceived.parts[s].shape == declared.parts[s].shape for s in SIDES])
    )
    surf, heights = [], []
    for part in ("on", "under"):
        if declared.parts[part].shape in ("flat", "open", "concave"):
            a = np.asarray(perceived.surface_size(part))
            b = np.asarray(declared.surface_size(part))
            surf.append(bool(np.all(np.abs(a - b) <= SIZE_TOL)))
        heights.append(
            abs(perceived.surface_height(part) - declared.surface_height(part)) <= HEIGHT_TOL
        )
    out["surface"] = float(np.mean(surf)) if surf else 1.0
    out["height"] = float(np.mean(heights))
    out["food"] = float(
        np.mean([perceived.parts[s].food_surface == declared.parts[s].food_surface for s in SIDES])
    )
    out["material"] = float(perceived.material == declared.material)
    out["mass"] = float(
        abs(math.log(max(perceived.mass, 1e-6) / declared.mass)) <= math.log(MASS_FACTOR)
    )
    out["mass_class"] = float(mass_class(perceived.mass) == mass_class(declared.mass))
    out["robustness"] = float(perceived.robustness == declared.robustness)
    return out


def mean_accuracy(rows: Iterable[Mapping[str, float]]) -> dict[str, float]:
    rows = list(rows)
    return {a: float(np.mean([r[a] for r in rows])) if rows else math.nan for a in ATTRIBUTES}


def build_perceived_scene(
    scene: Scene, seen: Mapping[str, ObjectType], perceive_s: float = 0.0
) -> PerceivedScene:
    """The planning scene and its mapping from per-object perceived types (`seen`: object ->
    type in its declared orientation, any name)."""
    types = {o: t._replace(name=seen_type_name(o)) for o, t in seen.items()}
    by_name = {t.name: t for t in types.values()}
    catalogue = scene.catalogue.merged(by_name)
    objects = tuple(
        o._replace(type=seen_type_name(o.name)) if o.name in types else o for o in scene.objects
    )
    planning = scene._replace(
        catalogue=catalogue,
        objects=objects,
        custom_types={**scene.custom_types, **by_name},
        goal_base=scene.tower_base,
    )
    members, acc = {}, []
    for o in scene.objects:
        if o.name not in types:
            continue
        declared = scene.type_of(o.name)
        members[o.name] = align_members(types[o.name], declared)
        acc.append(attribute_accuracy(types[o.name], declared, members[o.name]))
    return PerceivedScene(scene, planning, types, members, mean_accuracy(acc), perceive_s)


def perceive_scene(
    scene: Scene, seed: int = 0, *, backend: Any = None, perceiver: Perceiver | None = None
) -> PerceivedScene:
    """Look at the episode's world of (`scene`, `seed`) with the survey cameras and perceive
    every object (module docstring). `backend`: a `MujocoBackend` to reuse (it is reset);
    `perceiver`: any `utamp_gym.contract.perceiver.Perceiver` (default: the built-in one)."""
    return perceive_world(scene, run_seed(scene.name, seed), backend=backend, perceiver=perceiver)


def perceive_world(
    scene: Scene, world_seed: int, *, backend: Any = None, perceiver: Perceiver | None = None
) -> PerceivedScene:
    """`perceive_scene` of the world whose generator is seeded with `world_seed` (already
    derived from the scene and the run's seed: `utamp_gym.seeding.run_seed`). Without a
    `backend`, one of the default physics backend (`utamp_gym.backend.DEFAULT_BACKEND`) is
    built for the look."""
    own = backend is None
    sim = backend_factory(DEFAULT_BACKEND)() if own else backend
    start = time.perf_counter()
    try:
        sim.reset(scene, np.random.default_rng(world_seed))
        return perceive_live(scene, sim, start, perceiver=perceiver)
    finally:
        if own:
            sim.close()


def perceive_live(
    scene: Scene, backend: Any, start: float | None = None, *, perceiver: Perceiver | None = None
) -> PerceivedScene:
    """Perceive the world a backend simulates now (its survey look) with `perceiver` (the
    protocol's request: the views, the instance ids' object names and their orientations);
    `scene` is the declared scene (for the orientations and the alignment)."""
    start = time.perf_counter() if start is None else start
    request = PerceptionRequest(
        backend.survey(),
        {i: n for i, n in backend.cameras.instances.items() if n in scene.object_names},
        {o.name: o.orientation for o in scene.objects},
    )
    reports = dict((perceiver or BuiltinPerceiver()).perceive(request))
    seen = {n: r.type for n, r in reports.items() if n in scene.object_names}
    missing = [o.name for o in scene.objects if o.name not in seen]
    if missing:
        raise PerceptionError(f"no camera saw {', '.join(missing)} in {scene.name}")
    ps = build_perceived_scene(scene, seen, time.perf_counter() - start)
    return dataclasses.replace(ps, reports=reports)


class PerceptionError(UtampError):
    """The cameras did not see every object of the scene."""


def plan_perceived(
    scene: Scene,
    seed: int = 0,
    *,
    timeout: float = 30.0,
    search: str | None = None,
    deadline: Any = None,
    backend: Any = None,
    perceiver: Perceiver | None = None,
    doubt: float = DOUBT_THRESHOLD,
) -> tuple[PlanOutcome, PerceivedScene | None]:
    """`utamp2-perceived` on a declared scene: perceive it, turn the perceived attributes into
    affordances with the rules, and plan the declared scene with them. As for `utamp2-noisy`,
    the initial state (stacks, orientations, workspace and free spaces) is the scene's: the
    attributes are what is perceived. The facts are renamed to the declared members they
    overlap (`align_members`); those on perceived members with no declared counterpart have
    no symbol to plan with, but count as false positives in the scores (against the declared
    scene's ground truth). The planning time includes the perception (render and fit). A
    scene the cameras could not perceive is unsolved, with the reason (and no perceived
    scene). Attributes reported with a confidence below `doubt` are planned at their
    cautious values (`utamp_gym.methods.doubt`; the returned scene's ``doubt`` says how)."""
    start = time.perf_counter()
    try:
        ps = perceive_scene(scene, seed, backend=backend, perceiver=perceiver)
    except PerceptionError as exc:
        nothing = Scores(0.0, 0.0, 0.0, 0, 0, 0)
        reason = f"perception: {exc}"
        elapsed = time.perf_counter() - start
        outcome = PlanOutcome(
            scene.name, PERCEIVED, scene.n_objects, False, (), elapsed, reason, seed, nothing,
        )  # fmt: skip
        return outcome, None
    outcome, ps = plan_seen(
        scene, ps, seed=seed, timeout=timeout, search=search, deadline=deadline, doubt=doubt
    )
    return outcome._replace(planning_time_s=outcome.planning_time_s + ps.perceive_s), ps


def plan_seen(
    scene: Scene,
    ps: PerceivedScene,
    *,
    seed: int = 0,
    timeout: float = 30.0,
    search: str | None = None,
    deadline: Any = None,
    doubt: float = DOUBT_THRESHOLD,
) -> tuple[PlanOutcome, PerceivedScene]:
    """Plan `scene` with the affordances of a perceived scene, cautiously where in doubt
    (`plan_perceived`); a goal the cautious values make unsolvable is planned with the
    likely ones, and one those leave unsolvable, hoping (`utamp_gym.methods.doubt`: the
    values that promise most, and the facts some alternative allows); the returned
    scene's ``doubt`` says which. The scores are the likely values' (what was perceived),
    whichever values were planned with."""
    likely = plan_affordances(ps.planning)
    scores = ps.scores(likely, ground_truth_for(scene))  # perception, not caution

    def attempt(planned: PerceivedScene, facts: frozenset[Fact]) -> PlanOutcome:
        return plan_scene(
            scene, PERCEIVED, seed=seed, timeout=timeout, search=search, deadline=deadline,
            affordances=(planned.usable_facts(facts), scores),
        )  # fmt: skip

    cautious, doubts = cautious_types(ps.planning, ps.types, ps.reports, doubt)
    if doubts:
        planned = _with_types(scene, ps, cautious)
        outcome = attempt(planned, plan_affordances(planned.planning))
        if outcome.solved:
            return outcome, dataclasses.replace(planned, doubt=DoubtfulPlan(doubts))
    outcome = attempt(ps, likely)
    fell_back = dataclasses.replace(ps, doubt=DoubtfulPlan(doubts, fell_back=bool(doubts)))
    if outcome.solved:
        return outcome, fell_back
    hopeful, hopes = cautious_types(ps.planning, ps.types, ps.reports, doubt, hopeful=True)
    planned = _with_types(scene, ps, hopeful) if hopes else ps
    facts, tried = plan_affordances(planned.planning), likely
    for pairs in (False, True):  # one misreading before two: the likelier hopes first
        facts = facts | hoped_facts(
            planned.planning, planned.types, ps.reports, singles=not pairs, pairs=pairs
        )
        if facts == tried:  # nothing more to hope for
            continue
        tried = facts
        hoped = attempt(planned, facts)
        if hoped.solved:
            return hoped, dataclasses.replace(planned, doubt=DoubtfulPlan(hopes, hoped=True))
    return outcome, fell_back


def _with_types(
    scene: Scene, ps: PerceivedScene, types: Mapping[str, ObjectType]
) -> PerceivedScene:
    """`ps` planned with other `types` (object -> type), its reports kept."""
    seen = build_perceived_scene(scene, types)
    return dataclasses.replace(ps, planning=seen.planning, types=seen.types, members=seen.members)


def run_perceived_episode(
    scene: Scene,
    seed: int = 0,
    video: Any = None,
    *,
    pose_noise: float | None = None,
    disturbance: float = 0.0,
    perception: str = "gaussian",
) -> Any:
    """`utamp run --method utamp2-perceived`: perceive (through the simulator of the env the
    plan is then played in), plan, execute in the declared world (an
    `utamp_gym.agents.runs.EpisodeResult`)."""
    noise = DEFAULT_POSE_NOISE if pose_noise is None else pose_noise
    env = open_loop_env(
        scene.name, pose_noise=noise, disturbance=disturbance, perception=perception
    )
    try:
        t0 = time.perf_counter()
        outcome, _ = plan_perceived(scene, seed, backend=env.backend)
        return episode_result(
            scene.name, outcome, outcome.plan, seed, video, t0, None, noise, disturbance,
            perception, env=env,
        )  # fmt: skip
    finally:
        env.close()


__all__ = [
    "ATTRIBUTES",
    "PerceivedScene",
    "PerceptionError",
    "align_members",
    "attribute_accuracy",
    "build_perceived_scene",
    "perceive_live",
    "perceive_scene",
    "perceive_world",
    "plan_perceived",
    "plan_seen",
    "rename_fact",
    "run_perceived_episode",
    "seen_type_name",
]
