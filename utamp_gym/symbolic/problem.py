"""Symbolic state abstraction of a scene: the PDDL problem of U-TAMP-1 / U-TAMP-2.

Objects: the scene's objects, their members (``<object>-<member>``), the table slots
(each slot stands for the table top in its region), free spaces for sliding, and
the domain constants hand, air and workspace. The goal is the literals of a
`utamp_gym.tasks.goal.Goal`: the one given, else the scene's own (a scene file's
``[goal]``), else the paper's: the hand is empty and every slot except the tower base's
is clear, so all objects form one tower on the base, each standing directly on the one
below (`goal_atoms`; the problem text is then what it was before goals were data).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import NamedTuple

from utamp_gym.affordances.facts import Fact
from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene.geometry import NORMALS, OPPOSITE, SIDES, Box, is_adjacent
from utamp_gym.scene.model import STANDING_PART, UP_PART, Scene
from utamp_gym.symbolic.slots import Footprint, fits, usable_region
from utamp_gym.tasks.goal import Goal

DOMAINS = ("utamp2", "utamp1", "utamp2x")
AFFORDANCE_PREDICATES = {"utamp2": True, "utamp1": False, "utamp2x": True}
SPACE_CONTACT_GAP = 0.01  # m


def domain_text(domain: str) -> str:
    """PDDL text of a packaged domain."""
    if domain not in DOMAINS:
        raise UnknownNameError("domain", domain, DOMAINS)
    return asset_path("pddl", f"{domain}.pddl").read_text()


def member_symbol(obj: str, member: str) -> str:
    return f"{obj}-{member}"


def _base_part(inverted: bool) -> str:
    """The side facing the robot's edge of the table (-x): `back` for our yaw-0 objects.

    `base` is static in the domains, so it is defined by orientation, which pick and
    place preserve, rather than by the (changing) position; a half turn about x keeps it.
    """
    to_robot = (-1.0, 0.0)
    best, best_dot = "back", -math.inf
    for side in ("front", "back", "left", "right"):
        nx, ny = float(NORMALS[side][0]), float(NORMALS[side][1])
        if inverted:
            ny = -ny  # a half turn about x mirrors y
        d = nx * to_robot[0] + ny * to_robot[1]
        if d > best_dot + 1e-12:
            best, best_dot = side, d
    return best


class Problem(NamedTuple):
    """A generated problem: its PDDL text and the symbols it uses."""

    name: str
    domain: str
    text: str
    objects: tuple[str, ...]
    init: frozenset[str]
    goal: tuple[str, ...]


def _atom(*args: str) -> str:
    return "(" + " ".join(args) + ")"


def scene_facts(scene: Scene, affordances: Iterable[Fact], domain: str = "utamp2") -> set[str]:
    """Initial-state atoms of a scene."""
    if domain not in DOMAINS:
        raise UnknownNameError("domain", domain, DOMAINS)
    facts: set[str] = set()
    parts = (*SIDES, "in")
    for p in parts:
        facts.add(_atom("isPartEqual", p, p))
    for a in SIDES:
        facts.add(_atom("isOpposite", a, OPPOSITE[a]))
        for b in SIDES:
            if is_adjacent(a, b):
                facts.add(_atom("isAdjacent", a, b))
    symbols = ["hand", "air", "workspace"]
    facts.add(_atom("oc", "in", "hand", "air"))

    on_top: dict[str, str] = {o.on: o.name for o in scene.objects}
    for slot in scene.slots:
        symbols.append(slot.name)
        facts.add(_atom("force", slot.name, "on"))
        facts.add(_atom("base", slot.name, "back"))
        facts.add(_atom("oc", "on", slot.name, on_top.get(slot.name, "air")))
        region = Box(slot.region.min, (slot.region.max[0], slot.region.max[1], 0.0))
        if scene.workspace.contains_xy(region, tol=1e-6):
            facts.add(_atom("oc", "in", "workspace", slot.name))

    for o in scene.objects:
        symbols.append(o.name)
        t = scene.type_of(o.name)
        inverted = o.orientation == "inverted"
        stand, up = STANDING_PART[o.orientation], UP_PART[o.orientation]
        facts.add(_atom("force", o.name, up))
        facts.add(_atom("base", o.name, _base_part(inverted)))
        for side in SIDES:
            if side == stand:
                facts.add(_atom("oc", side, o.name, o.on))
            elif side == up:
                facts.add(_atom("oc", side, o.name, on_top.get(o.name, "air")))
            else:
                facts.add(_atom("oc", side, o.name, "air"))
        support_up = (
            "on"
            if o.on in {s.name for s in scene.slots}
            else UP_PART[scene.object(o.on).orientation]
        )
        facts.add(_atom("oc", support_up, o.on, o.name))
        if scene.in_workspace(scene.world_box(o.name)):
            facts.add(_atom("oc", "in", "workspace", o.name))
        for mname in t.members:
            m = member_symbol(o.name, mname)
            symbols.append(m)
            facts.add(_atom("isMember", o.name, m))
            if scene.in_workspace(scene.world_box(o.name, mname)):
                facts.add(_atom("oc", "in", "workspace", m))

    for space in scene.spaces:
        symbols.append(space.name)
        facts.add(_atom("oc", "on", space.slot, space.name))
        facts.add(_atom("oc", "under", space.name, space.slot))
        box = space.box
        occupied = False
        for name in scene.stacks.get(space.slot, ()):
            obox = scene.world_box(name)
            if box.overlaps_xy(obox, tol=1e-6):
                occupied = True
            # compare footprints only: give both the same unit height
            foot = Box((*obox.min[:2], 0.0), (*obox.max[:2], 1.0))
            space_foot = Box((*box.min[:2], 0.0), (*box.max[:2], 1.0))
            for side in ("front", "back", "left", "right"):
                if foot.touches_side(space_foot, side, SPACE_CONTACT_GAP):
                    facts.add(_atom("oc", side, name, space.name))
                    facts.add(_atom("oc", OPPOSITE[side], space.name, name))
        if not occupied:
            facts.add(_atom("oc", "in", space.name, "air"))
        ws_box = Box(box.min, (box.max[0], box.max[1], 0.0))
        if scene.workspace.contains_xy(ws_box, tol=1e-6):
            facts.add(_atom("oc", "in", "workspace", space.name))

    for s in symbols:
        facts.add(_atom("isObjEqual", s, s))
    if AFFORDANCE_PREDICATES[domain]:
        facts |= instantiate_affordances(scene, affordances)
    return facts


def instantiate_affordances(scene: Scene, affordances: Iterable[Fact]) -> set[str]:
    """Type-level facts -> atoms over the scene's objects. Slots inherit the table's facts,
    for the objects they admit (`symbolic.slots.admits`: inside the region, within reach)."""
    by_type: dict[str, list[str]] = {}
    for o in scene.objects:
        by_type.setdefault(o.type, []).append(o.name)
    by_type.setdefault(scene.table_type, []).extend(s.name for s in scene.slots)
    slots = {s.name: s for s in scene.slots}
    admitted: dict[tuple[str, str, str], bool] = {}  # (slot, type, part): `slots.admits`
    regions: dict[str, Box] = {}  # slot -> its usable region
    footprints: dict[tuple[str, str], Footprint] = {}  # (type, part)
    out: set[str] = set()
    for f in affordances:
        pred = f[0]
        if pred in ("isSupportive", "isSupportable"):
            for inst in by_type.get(f[1], []):
                out.add(_atom(pred, inst, f[2]))
        elif pred == "isP2PSupportive":
            p2, t2, p1, t1 = f[1:]
            for i2 in by_type.get(t2, []):
                for i1 in by_type.get(t1, []):
                    if i1 == i2:
                        continue
                    if i2 in slots:
                        key = (i2, t1, p1)
                        if key not in admitted:
                            if i2 not in regions:
                                regions[i2] = usable_region(scene, slots[i2])
                            if (t1, p1) not in footprints:
                                footprints[t1, p1] = Footprint.of(scene.type_of(i1), p1)
                            admitted[key] = fits(regions[i2], slots[i2], footprints[t1, p1])
                        if not admitted[key]:
                            continue
                    out.add(_atom(pred, p2, i2, p1, i1))
        elif pred == "canGraspFrom":
            t, member, hp, hf1, hf2 = f[1:]
            for inst in by_type.get(t, []):
                if member in scene.type_of(inst).members:
                    out.add(_atom(pred, inst, member_symbol(inst, member), hp, hf1, hf2))
        elif pred == "canLift":
            for inst in by_type.get(f[1], []):
                if f[2] in scene.type_of(inst).members:
                    out.add(_atom(pred, inst, member_symbol(inst, f[2])))
        elif pred == "canEdgePinch":  # the extended domain's (`affordances.edge`)
            t, member, hp, hf1, hf2 = f[1:]
            for inst in by_type.get(t, []):
                out.add(_atom(pred, inst, member_symbol(inst, member), hp, hf1, hf2))
        elif pred in ("canSlide", "canSlideEdge"):
            t1, t2, p1, p2 = f[1:]
            for i1 in by_type.get(t1, []):
                for i2 in by_type.get(t2, []):
                    out.add(_atom(pred, i1, i2, p1, p2))
    return out


def goal_atoms(scene: Scene) -> tuple[str, ...]:
    """Hand empty; every slot except the tower base's is clear."""
    base_slot = scene.slot_of(scene.tower_base)
    clear = [_atom("oc", "on", s.name, "air") for s in scene.slots if s.name != base_slot]
    return (_atom("oc", "in", "hand", "air"), *clear)


def problem_goal(scene: Scene, goal: Goal | None = None) -> tuple[str, ...]:
    """The goal literals a problem gets: `goal`'s, else the scene's, else the paper's."""
    if goal is None:
        goal = scene.goal
    return goal_atoms(scene) if goal is None else goal.literals


def build_problem(
    scene: Scene, affordances: Iterable[Fact], domain: str = "utamp2", goal: Goal | None = None
) -> Problem:
    """The PDDL problem for `scene` under `domain` with the given affordance facts and goal
    (`problem_goal`)."""
    init = frozenset(scene_facts(scene, affordances, domain))
    goal_lits = problem_goal(scene, goal)
    objects = [s.name for s in scene.slots] + [s.name for s in scene.spaces]
    for o in scene.objects:
        objects.append(o.name)
        objects.extend(member_symbol(o.name, m) for m in scene.type_of(o.name).members)
    pname = "utamp-" + scene.name.replace("/", "-")
    lines = [f"(define (problem {pname})", f"  (:domain {domain})", "  (:objects"]
    lines.append("    " + " ".join(objects) + " - obj)")
    lines.append("  (:init")
    lines.extend(f"    {a}" for a in sorted(init))
    lines.append("  )")
    lines.append("  (:goal (and")
    lines.extend(f"    {g}" for g in goal_lits)
    lines.append("  ))")
    lines.append(")")
    return Problem(pname, domain, "\n".join(lines) + "\n", tuple(objects), init, goal_lits)
