"""`utamp2-perceived`: look at the scene with the cameras, plan with the perceived attributes.

The perceiver (`utamp_gym.perception.objects`) only gets the rendered views. This module,
in the evaluation layer, may read the scene, and does what needs both:

* `perceive_scene` resets the physics backend to the episode's world (the same seed gives
  the same initial poses and colours as the physics run), takes the survey look, perceives
  every object and writes each as its own catalogue type (``<object>-seen``) in the object's
  declared orientation; the *planning scene* is the declared scene with those types, so the
  rule parser (`affordances.rules`) turns perceived attributes into the affordances the
  planner uses;
* `align_members` pairs each perceived member with a declared one by box overlap (the
  perceiver names members by kind and side, the catalogue by its own convention): the
  plan's member symbols and the perceived facts are renamed through it, for scoring against
  the ground truth and for executing the plan in the declared world; a perceived member
  with no declared counterpart keeps its name (its facts are false positives, an action on
  it fails);
* `attribute_accuracy` compares every perceived attribute with the declared one
  (`ATTRIBUTES`), per object, for the eval rows.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from utamp_gym.affordances.facts import Fact, Scores, score
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import SIDES, Box
from utamp_gym.scene.model import Scene

SEEN_SUFFIX = "-seen"
#: per-attribute accuracy columns of the eval rows (fractions of objects / parts / members)
ATTRIBUTES = (
    "body",  # body primitive (box or cylinder)
    "members",  # members found (Dice of matched members)
    "member_size",  # matched members' boxes within SIZE_TOL in every extent
    "shape",  # part shapes (six sides)
    "surface",  # usable surface sizes of on/under within SIZE_TOL
    "height",  # usable surface heights of on/under within HEIGHT_TOL
    "food",  # food-surface flags
    "material",
    "mass",  # within a factor MASS_FACTOR
    "robustness",
)
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
    if pred == "canSlide":
        return (pred, types.get(fact[1], fact[1]), types.get(fact[2], fact[2]), *fact[3:])
    t = fact[1]
    if pred in ("canGraspFrom", "canLift"):
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

    def declared_facts(self, facts: Iterable[Fact]) -> frozenset[Fact]:
        """Facts over the perceived types, in the declared types' and members' names."""
        types = {seen_type_name(o.name): o.type for o in self.declared.objects}
        members = {seen_type_name(o): m for o, m in self.members.items()}
        return frozenset(rename_fact(f, types, members) for f in facts)

    def scores(self, facts: Iterable[Fact], truth: Iterable[Fact]) -> Scores:
        return score(self.declared_facts(facts), truth)

    def declared_action(self, action: str) -> str:
        """A planned action with each perceived member symbol renamed to the declared one
        (``obj-handle-back`` -> ``obj-handle``); an unmatched member keeps its symbol."""
        tokens = action.strip().strip("()").split()
        if len(tokens) < 3:
            return action
        obj, symbol = tokens[1], tokens[2]
        member = symbol.removeprefix(f"{obj}-")
        declared = self.members.get(obj, {}).get(member)
        if declared is not None:
            tokens[2] = f"{obj}-{declared}"
        return "(" + " ".join(tokens) + ")"

    def declared_plan(self, plan: Sequence[str]) -> tuple[str, ...]:
        return tuple(self.declared_action(a) for a in plan)


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


__all__ = [
    "ATTRIBUTES",
    "PerceivedScene",
    "align_members",
    "attribute_accuracy",
    "build_perceived_scene",
    "rename_fact",
    "seen_type_name",
]
