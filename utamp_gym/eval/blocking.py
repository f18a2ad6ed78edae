"""Why a scene is unsolvable under its ground-truth affordances: the blocked goal atoms and
the rules that refuse them, with their numbers.

The goal is one tower on the base: every slot but the base's cleared (`goal_atoms`). An
object joins the tower when it can be picked up (a ``canGraspFrom`` with its palm on the
part facing up and a ``canLift`` of that member) and an object already in it carries it
(``isSupportive`` of that object's top, ``isP2PSupportive`` onto it, ``isSupportable`` of
the part it stands on). From the base's stack, objects join until none can: the slot of an
object left out cannot be cleared. For each such object, each refused fact is asked of the
rule that decides it (`utamp_gym.affordances.rules`, the ``*_refusal`` twins): the rule's
name and the numbers it compared. A fact that the rules would grant but the hand-written
ground truth lacks is named as such. Fast Downward then checks the rest of the goal without
the blocked atoms (`SolvabilityOracle`). When every object can join the tower on its own but
the planner finds no order that stacks them all, each object without which the others do
stack is named, with its goal atom (rule ``one-tower``; an object above it takes its place).

A scene with a goal of its own (`Scene.goal`, other than the tower template: procedural-v2)
is explained by its goal's literals instead (`goal_blocks`): each literal the scene does not
satisfy yet names the objects that must move (the one that must stand on a target, be put in
a region or taken off something; everything standing on a surface to clear or on the target
of such a move), and each such object is asked whether it can be picked up and put down
where the goal allows (on its target; on the table if the goal leaves it a region; else on
an object the goal allows that carries it), with the refusing rules as for the tower. Block
atoms are then the goal's literals (``(not (oc under obj3 slot1))`` included). When every
such move is possible on its own, the order or the room of the moves blocks the goal (rule
``goal-order``): the literals Fast Downward finds unreachable even alone, else each without
which the rest is reachable (`_goal_order`).

In the extended domain (``utamp2x``, procedural-v2's labelling domain) a pick-up is asked of
the extended rules (`rules.pick_refusal` with ``extended``) and, for a member taken from
above, of the rim pinch too (`utamp_gym.affordances.rim.rim_pinch_refusal`): both refusals
are named (``cannot be picked up by ...`` first, then ``cannot be pinched at the rim by
...``).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, NamedTuple

from utamp_gym.affordances import rules
from utamp_gym.affordances.facts import Fact, score
from utamp_gym.affordances.rim import rim_pinch_refusal
from utamp_gym.affordances.sources import EXTENDED_DOMAINS
from utamp_gym.affordances.why import Refusal
from utamp_gym.eval.solvability import SolvabilityOracle
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.model import STANDING_PART, UP_PART, Scene, SceneObject
from utamp_gym.symbolic.problem import goal_atoms
from utamp_gym.tasks.goal import HAND_EMPTY, Goal, split_literal

#: rules of the grasp's later tests first: the closest the object came to being picked up
_PICK_ORDER = ("ground-truth", "torque", "payload", "finger-room", "hand-room", "pinch")
#: ... and of a rim pinch's (the extended domain's), after every grasp's
_PINCH_ORDER = ("rim-payload", "torque", "rim-finger-room", "hand-room", "rim-flare", "rim-width")
NO_ONE_HELPS = "leaving out any one object does not let the others stack"


def format_fact(fact: Fact) -> str:
    """``isP2PSupportive(on, frying-pan, under, cutting-board)``."""
    return f"{fact[0]}({', '.join(fact[1:])})"


class Block(NamedTuple):
    """One reason a goal atom cannot be reached.

    `stage` is ``pick`` (the object cannot be picked up by the grasp `subject` names),
    ``stand`` (it cannot be put down on the part it stands on), ``place`` (the object in the
    tower that `subject` names does not carry it), ``tower`` (no order stacks everything) or
    ``order`` (a goal's literal no order of possible moves reaches, `_goal_order`).
    """

    atom: str
    object: str
    type_name: str  # the object's type ("type" in the JSON)
    stage: str
    subject: str
    refusal: Refusal

    @property
    def text(self) -> str:
        return f"{self.atom}: {self.subject}: {self.refusal.detail} [{self.refusal.rule}]"

    def to_json(self) -> dict[str, Any]:
        head = {"atom": self.atom, "object": self.object, "type": self.type_name}
        head |= {"stage": self.stage, "subject": self.subject}
        return head | self.refusal.to_json() | {"text": self.text}


def _pickable(facts: frozenset[Fact], o: SceneObject) -> bool:
    """A grasp with the palm on the part facing up, of a member it can be lifted by."""
    t, palm = o.type, UP_PART[o.orientation]
    return any(
        f[0] == "canGraspFrom" and f[1] == t and f[3] == palm and ("canLift", t, f[2]) in facts
        for f in facts
    )


def _carry_facts(y: SceneObject, o: SceneObject) -> tuple[Fact, ...]:
    """The facts `y` carrying `o` (each in its scene orientation) needs."""
    up, stand = UP_PART[y.orientation], STANDING_PART[o.orientation]
    return (
        ("isSupportive", y.type, up),
        ("isP2PSupportive", up, y.type, stand, o.type),
        ("isSupportable", o.type, stand),
    )


def _carries(facts: frozenset[Fact], y: SceneObject, o: SceneObject) -> bool:
    return all(f in facts for f in _carry_facts(y, o))


def tower(scene: Scene, facts: frozenset[Fact]) -> set[str]:
    """The objects that can end in the goal tower (a delete-relaxed fixed point)."""
    joined = set(scene.stacks.get(scene.slot_of(scene.tower_base), ()))
    changed = True
    while changed:
        changed = False
        for o in scene.objects:
            if o.name in joined or not _pickable(facts, o):
                continue
            if any(_carries(facts, scene.object(y), o) for y in joined):
                joined.add(o.name)
                changed = True
    return joined


def _or_truth(refusal: Refusal | None, missing: Iterable[Fact]) -> Refusal:
    """The rule's refusal, or (the rules grant it) the fact the ground truth lacks."""
    if refusal is not None:
        return refusal
    return Refusal("ground-truth", {"fact": ", ".join(map(format_fact, missing))})


def _pick_blocks(
    facts: frozenset[Fact], t: ObjectType, o: SceneObject, extended: bool = False
) -> list[tuple[str, Refusal]]:
    """(subject, refusal) for each distinct refusal of the grasps from the part facing up
    (`extended`: the extended domain's rules, rim pinches included); the subject reads
    ``cannot be picked up by GRASPS`` or ``cannot be pinched at the rim by GRASPS``."""
    palm = UP_PART[o.orientation]
    grasps: dict[tuple[str, str], list[str]] = {}
    refusals: dict[tuple[str, str], Refusal] = {}
    for member in t.members:
        for f1, f2 in rules.FINGER_PAIRS:
            grasp = ("canGraspFrom", t.name, member, palm, f1, f2)
            missing = [f for f in (grasp, ("canLift", t.name, member)) if f not in facts]
            said = [("picked up by", rules.pick_refusal(t, member, palm, f1, f2, extended))]
            if extended and palm == "on" and t.members[member].kind in ("edge", "body"):
                said.append(("pinched at the rim by", rim_pinch_refusal(t, member, palm, f1, f2)))
            if any(r is None for _, r in said):  # the rules grant it: the facts lack it
                said = [("picked up by", None)]
            for how, r in said:
                refusal = _or_truth(r, missing)
                # the same test with the same numbers (the mass, for every handle) is said once
                key = (how, refusal.detail)
                refusals.setdefault(key, refusal)
                grasps.setdefault(key, []).append(f"{member} ({f1}/{f2})")
    ranks = {"picked up by": _PICK_ORDER, "pinched at the rim by": _PINCH_ORDER}

    def rank(how: str, rule: str) -> tuple[bool, int]:
        order = ranks[how]
        return how != "picked up by", order.index(rule) if rule in order else len(order)

    keys = sorted(refusals, key=lambda k: rank(k[0], refusals[k].rule))
    return [(f"{how} {', '.join(grasps[how, d])}", refusals[how, d]) for how, d in keys]


def object_blocks(
    scene: Scene,
    facts: frozenset[Fact],
    name: str,
    joined: set[str],
    atom: str,
    extended: bool = False,
) -> list[Block]:
    """Why object `name` cannot join the tower `joined` (its goal atom `atom`; `extended`:
    asked of the extended domain's rules)."""
    o = scene.object(name)
    t = scene.catalogue[o.type]
    label = _label(o)
    blocks: list[Block] = []

    def block(stage: str, subject: str, refusal: Refusal) -> None:
        blocks.append(Block(atom, name, o.type, stage, subject, refusal))

    if not _pickable(facts, o):
        for grasps, refusal in _pick_blocks(facts, t, o, extended):
            block("pick", f"{label} cannot be {grasps}", refusal)
    stand = STANDING_PART[o.orientation]
    supportable = ("isSupportable", o.type, stand)
    if supportable not in facts:
        refusal = _or_truth(rules.supportable_refusal(t, stand), [supportable])
        block("stand", f"{label} cannot be put down on its {stand}", refusal)
        return blocks
    base = scene.tower_base  # the base first, then the others by name
    supporters = [scene.object(y) for y in sorted(joined, key=lambda y: (y != base, y))]
    supporters = [y for y in supporters if y.name != name]
    if any(_carries(facts, y, o) for y in supporters):
        return blocks
    for y in supporters:
        up = UP_PART[y.orientation]
        ty = scene.catalogue[y.type]
        missing = [f for f in _carry_facts(y, o) if f not in facts]
        refusal = _or_truth(rules.p2p_refusal(ty, up, t, stand), missing)
        block("place", f"{_label(y)} does not carry {label}", refusal)
    for y in scene.objects:  # what would carry it, but cannot join the tower itself
        if y.name != name and y.name not in joined and _carries(facts, y, o):
            refusal = Refusal("off-tower", {"supporter": y.name, "type": o.type})
            block("place", f"{_label(y)} would carry {label}", refusal)
    return blocks


def blocking_goals(
    scene: Scene,
    facts: Iterable[Fact],
    oracle: SolvabilityOracle | None = None,
    domain: str = "utamp2",
) -> tuple[tuple[Block, ...], bool | None]:
    """The blocks of an unsolvable `scene` under `facts`, and whether the rest of the goal
    is solvable without their atoms (None: not checked, no `oracle`). The refusals are the
    rules of `domain` (``utamp2x``: the extended grasps and rim pinches too; the
    `oracle`'s own domain when given)."""
    facts = frozenset(facts)
    if oracle is not None:
        domain = oracle.domain
    extended = domain in EXTENDED_DOMAINS
    if scene.goal is not None and scene.goal.template != "tower":
        blocks = goal_blocks(scene, facts, scene.goal, extended)
        if oracle is None:
            return blocks, None
        if not blocks:  # every move is possible on its own: the order or the room blocks
            blocks = _goal_order(scene, facts, oracle)
        blocked = {split_literal(b.atom)[1] for b in blocks}
        return blocks, oracle(facts, [g for g in oracle.goal if g not in blocked])
    joined = tower(scene, facts)
    slot_atom = dict(zip((s.name for s in scene.slots), _slot_atoms(scene), strict=True))
    blocks: list[Block] = []
    for o in scene.objects:
        if o.name not in joined:
            atom = slot_atom[scene.slot_of(o.name)]
            blocks += object_blocks(scene, facts, o.name, joined, atom, extended)
    if oracle is None:
        return tuple(blocks), None
    goal = oracle.goal
    if blocks:
        blocked = {b.atom for b in blocks}
        return tuple(blocks), oracle(facts, [g for g in goal if g not in blocked])
    # every object joins the tower on its own: no order stacks them all
    return _one_tower(scene, facts, slot_atom, oracle.timeout, domain), None


def _without(scene: Scene, name: str) -> Scene:
    """`scene` without object `name` (what stood on it takes its place)."""
    gone = scene.object(name)
    objects = tuple(
        o._replace(on=gone.on, position=gone.position) if o.on == name else o
        for o in scene.objects
        if o.name != name
    )
    return scene._replace(objects=objects)


def _one_tower(
    scene: Scene,
    facts: frozenset[Fact],
    slot_atom: dict[str, str],
    timeout: float,
    domain: str = "utamp2",
) -> tuple[Block, ...]:
    """Objects without which the others stack under `facts` (all that must move if there
    is none)."""
    movable = [o for o in scene.objects if slot_atom[scene.slot_of(o.name)]]
    given = (facts, score(facts, facts))

    def stacks(rest: Scene) -> bool:
        if all(not slot_atom[rest.slot_of(o.name)] for o in rest.objects):
            return True  # only the base's stack is left: the goal holds already
        return plan_scene(rest, f"{domain}-gt", timeout=timeout, affordances=given).solved

    spoilers = [o for o in movable if stacks(_without(scene, o.name))]
    blocks = []
    for o in spoilers or movable:
        rest = f"without {o.name}, the others stack" if spoilers else NO_ONE_HELPS
        refusal = Refusal("one-tower", {"object": o.name, "rest": rest})
        atom = slot_atom[scene.slot_of(o.name)]
        blocks.append(Block(atom, o.name, o.type, "tower", _label(o), refusal))
    return tuple(blocks)


def _label(o: SceneObject) -> str:
    """``pan (frying-pan)``, ``mug (glass-mug, upside down)``."""
    return f"{o.name} ({o.type}{', upside down' if o.orientation == 'inverted' else ''})"


def _slot_atoms(scene: Scene) -> list[str]:
    """Each slot's goal atom, ``(oc on SLOT air)``, in slot order ("" for the base's slot,
    which the goal does not clear)."""
    atoms = set(goal_atoms(scene))
    return [
        f"(oc on {s.name} air)" if f"(oc on {s.name} air)" in atoms else "" for s in scene.slots
    ]


# ------------------------------------------------------------------ a scene's own goal
class _Move(NamedTuple):
    """An object a goal literal makes move, and where the goal lets it stand: `target` (one
    support) or, when None, anything but `excluded`."""

    literal: str
    object: str
    target: str | None
    excluded: frozenset[str]


def _moves(scene: Scene, goal: Goal) -> list[_Move]:
    """The objects the goal's literals unmet in the scene make move (the hand's literal
    always holds at the start)."""
    objects, slots = set(scene.object_names), {s.name for s in scene.slots}
    excluded: dict[str, set[str]] = {}  # per object, the supports its negations rule out
    for lit in goal.literals:
        positive, a = split_literal(lit)
        _, _, x, y = a.strip("()").split()
        if not positive and x in objects:
            excluded.setdefault(x, set()).add(y)
    moves = []
    for lit in goal.literals:
        positive, a = split_literal(lit)
        _, _, x, y = a.strip("()").split()
        if x == "hand":
            continue
        if y == "air":  # clear a surface: everything standing on it moves
            if positive:
                moves += [
                    _Move(lit, o.name, None, frozenset({x, *excluded.get(o.name, ())}))
                    for o in scene.objects
                    if o.on == x
                ]
        elif x in slots:  # an object in a region
            if positive and scene.object(y).on != x:
                moves.append(_Move(lit, y, x, frozenset()))
        elif positive and scene.object(x).on != y:  # x must stand on y
            moves.append(_Move(lit, x, y, frozenset()))
        elif not positive and scene.object(x).on == y:  # x must leave y
            moves.append(_Move(lit, x, None, frozenset(excluded.get(x, ()))))
    for m in [m for m in moves if m.target is not None]:  # what stands on a target moves off
        moves += [
            _Move(m.literal, o.name, None, frozenset({m.target, *excluded.get(o.name, ())}))
            for o in scene.objects
            if o.on == m.target and o.name != m.object
        ]
    return moves


def _put_blocks(scene: Scene, facts: frozenset[Fact], m: _Move) -> list[tuple[str, Refusal]]:
    """(subject, refusal) for each reason `m.object` cannot be put down where the goal
    allows (none: it can)."""
    o = scene.object(m.object)
    t, stand, label = scene.catalogue[o.type], STANDING_PART[o.orientation], _label(o)
    slots = [s.name for s in scene.slots]
    if m.target is not None:
        allowed = [m.target]
    else:
        allowed = [z for z in (*slots, *scene.object_names) if z != o.name]
        allowed = [z for z in allowed if z not in m.excluded]
    supportable = ("isSupportable", o.type, stand)
    out: list[tuple[str, Refusal]] = []
    if any(z in slots for z in allowed):
        if supportable in facts:
            return []
        refusal = _or_truth(rules.supportable_refusal(t, stand), [supportable])
        out.append((f"{label} cannot be put down on its {stand}", refusal))
    for z in (z for z in allowed if z not in slots):
        y = scene.object(z)
        if _carries(facts, y, o):
            return []
        missing = [f for f in _carry_facts(y, o) if f not in facts]
        refusal = _or_truth(rules.p2p_refusal(scene.catalogue[y.type], UP_PART[y.orientation],
                                              t, stand), missing)  # fmt: skip
        out.append((f"{_label(y)} does not carry {label}", refusal))
    return out


def goal_blocks(
    scene: Scene, facts: Iterable[Fact], goal: Goal, extended: bool = False
) -> tuple[Block, ...]:
    """Why the goal's literals cannot be reached under `facts`: per literal the scene does
    not satisfy, each object it makes move that cannot be picked up (stage ``pick``) or put
    down where the goal allows (``stand``: on the table; ``place``: on an object).
    `extended`: the pick-ups are asked of the extended domain's rules (rim pinches too)."""
    facts = frozenset(facts)
    blocks: list[Block] = []
    for m in _moves(scene, goal):
        o = scene.object(m.object)
        t, label = scene.catalogue[o.type], _label(o)
        if not _pickable(facts, o):
            for grasps, refusal in _pick_blocks(facts, t, o, extended):
                subject = f"{label} cannot be {grasps}"
                blocks.append(Block(m.literal, o.name, o.type, "pick", subject, refusal))
        for subject, refusal in _put_blocks(scene, facts, m):
            stage = "stand" if subject.startswith(label) else "place"
            blocks.append(Block(m.literal, o.name, o.type, stage, subject, refusal))
    return tuple(blocks)


def _goal_order(
    scene: Scene, facts: frozenset[Fact], oracle: SolvabilityOracle
) -> tuple[Block, ...]:
    """The literals of a goal no order of moves reaches although each object it moves can be
    picked up and put down where it allows (rule ``goal-order``): those unreachable even
    alone (with the hand empty), else each without which the rest is reachable, else all."""
    assert scene.goal is not None
    slots = {sl.name for sl in scene.slots}
    literals = [lit for lit in scene.goal.literals if lit != HAND_EMPTY]
    hand = [HAND_EMPTY] if HAND_EMPTY in oracle.goal else []

    def atom_of(lit: str) -> str:
        return split_literal(lit)[1]

    alone = [lit for lit in literals if not oracle(facts, [*hand, atom_of(lit)])]
    why = {lit: "not even alone" for lit in alone}
    if not alone:
        for lit in literals:
            rest = [atom_of(k) for k in literals if k != lit]
            if oracle(facts, [*hand, *rest]):
                why[lit] = "without it, the rest of the goal is reachable"
    if not why:
        why = {lit: "leaving out any one literal does not make the rest reachable"
               for lit in literals}  # fmt: skip
    blocks = []
    for lit, reason in why.items():
        _, _, x, y = atom_of(lit).strip("()").split()
        o = scene.object(y if x in slots else x)
        refusal = Refusal("goal-order", {"literal": lit, "why": reason})
        blocks.append(Block(lit, o.name, o.type, "order", _label(o), refusal))
    return tuple(blocks)
