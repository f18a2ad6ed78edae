"""Geometric preconditions: U-TAMP-2's actions without the affordance literals.

Why: with masks "geometric" (and "none") an agent must not be told what the affordances
allow, yet it must be able to try everything the object-centric constraints allow. That is
U-TAMP-1's view (Agostini and Piater): `geometric_domain` is U-TAMP-2's domain with every
affordance literal dropped from the preconditions (`GEOMETRIC_DROPPED`: ``canGraspFrom``,
``canLift`` and ``not canLift``, ``isSupportive``, ``isSupportable``, ``isP2PSupportive``,
``canSlide``) and U-TAMP-1's object-centric grasp constraint added (`GRASP_GEOMETRY`), so the
actions include side and body grasps of the shaker, lifting the tray, placing on round tops,
with U-TAMP-2's effects and its slide action.

`isSupportable` is dropped with the other five: the paper introduces it with the affordances
(Sec. IV "Supportability", Table I) and U-TAMP-1 has no such predicate. With orientations kept
by pick and place it decides nothing in our suites anyway: an object only ever rests on the
part it stands on in its initial (allowed) orientation.

Without the affordances, relaxed reachability over the union of a suite's scenes reaches
many ops that no real state allows (a shaker picked from a board it carries, grasps with a
finger on the part the object stands on). `prune` drops them with invariants of every
reachable state: the `IMPLIED` literals, and exactly-one groups (a part of an object touches
one thing; the hand holds one thing) of which an op would need two atoms at once; then it
drops the ops whose preconditions only such ops could reach. None of this changes the mask
of a reachable state; a few percent of the remaining ops still never apply (relaxed
reachability mixes atoms of different scenes, e.g. the upright and the inverted mug).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from functools import lru_cache
from types import MappingProxyType

from utamp_gym.affordances.facts import PREDICATES as AFFORDANCE_PREDICATES
from utamp_gym.symbolic.atoms import parse_atom
from utamp_gym.symbolic.pddl import Atom, Domain, Literal, parse_domain
from utamp_gym.symbolic.problem import domain_text
from utamp_gym.symbolic.reach import GroundOp

#: the affordance predicates (Table I) the geometric preconditions leave out: all six
GEOMETRIC_DROPPED = frozenset(p.lower() for p in AFFORDANCE_PREDICATES)
#: U-TAMP-1's StableGrasp without affordances: palm next to finger 1, the fingers opposite
GRASP_GEOMETRY = ("(isAdjacent ?o1-hp ?o1-hf1)", "(isOpposite ?o1-hf1 ?o1-hf2)")
#: true in every reachable state (what an object rests on touches it with its up-facing
#: part), stated so that grounding drops picks out of impossible two-object cycles
IMPLIED = MappingProxyType(
    {"pick-support": ("(force ?obj2 ?o2-o1)",), "slide-support": ("(force ?obj2 ?o2-o1)",)}
)


@lru_cache(maxsize=1)
def geometric_domain() -> Domain:
    """U-TAMP-2 without affordance literals, plus U-TAMP-1's grasp geometry (module docstring).

    Effects are U-TAMP-2's, so an action's outcome, when it succeeds, is the same in both.
    """
    domain = parse_domain(domain_text("utamp2"), source="utamp2.pddl")

    def literals(atoms: Iterable[str]) -> tuple[Literal, ...]:
        return tuple(Literal(parse_atom(a), True) for a in atoms)  # keeps the ?variables

    actions = {}
    for name, act in domain.actions.items():
        kept = tuple(lit for lit in act.precondition if lit.atom.predicate not in GEOMETRIC_DROPPED)
        grasps = any(lit.atom.predicate == "isgraspfrom" and not lit.positive for lit in kept)
        extra = literals((*(GRASP_GEOMETRY if grasps else ()), *IMPLIED.get(name, ())))
        actions[name] = act._replace(precondition=kept + extra)
    return domain._replace(
        name="utamp2-geometric",
        actions=MappingProxyType(actions),
        source="utamp2.pddl without affordance preconditions",
    )


def _exclusive_groups(
    ops: Sequence[GroundOp], inits: Sequence[tuple[frozenset[str], frozenset[str]]]
) -> dict[Atom, int]:
    """Atom -> group id, for groups of which exactly one atom holds in every reachable state.

    A group is the atoms sharing a predicate and all arguments but the last (as in
    `planning.sas`): exactly one holds initially in every scene that has the objects they
    name (`inits`: (fluent atoms, objects) per scene), and every op that makes one true
    requires and deletes another; no op requires one to be false. (By induction, an op
    requiring two of them never applies, so it cannot break the group.)
    """
    candidates: dict[tuple[str, tuple[str, ...]], set[Atom]] = defaultdict(set)
    touching: dict[Atom, list[int]] = defaultdict(list)  # atom -> ops mentioning it
    for i, op in enumerate(ops):
        for a in {*op.pre, *op.add, *op.delete}:
            touching[a].append(i)
            if a.args:
                candidates[(a.predicate, a.args[:-1])].add(a)
    negated = {a for op in ops for a in op.pre_neg}
    groups: dict[Atom, int] = {}
    for (_, prefix), members in candidates.items():
        if len(members) < 2 or members & negated:
            continue
        texts = {str(a) for a in members}
        if any(len(texts & fluent) != 1 for fluent, objs in inits if set(prefix) <= objs):
            continue
        relevant = {i for a in members for i in touching[a]}
        if all(_keeps_one(ops[i], members) for i in relevant):
            gid = len(set(groups.values()))
            groups.update(dict.fromkeys(members, gid))
    return groups


def _keeps_one(op: GroundOp, members: set[Atom]) -> bool:
    """Whether `op` keeps exactly one of `members` true (or can never apply)."""
    required = [a for a in op.pre if a in members]
    if len(required) > 1:
        return True
    made = [a for a in op.add if a in members and a not in op.pre]
    lost = [a for a in op.delete if a in members and a not in op.add]
    return len(made) == len(lost) <= 1 and all(a in op.pre for a in lost)


def _possible(op: GroundOp, groups: Mapping[Atom, int]) -> bool:
    """False if `op` requires two atoms of one exclusive group (it can never apply)."""
    seen: dict[int, Atom] = {}
    for a in op.pre:
        g = groups.get(a)
        if g is not None and seen.setdefault(g, a) != a:
            return False
    return True


def _reachable(ops: Sequence[GroundOp], init: Iterable[Atom]) -> list[GroundOp]:
    """The ops whose positive fluent preconditions are reachable (delete relaxation) from
    `init` using only `ops`: pruning impossible ops can cut off atoms only they added."""
    reached = set(init)
    pending = list(ops)
    while True:
        ready = [op for op in pending if all(a in reached for a in op.pre)]
        if not ready:
            break
        pending = [op for op in pending if not all(a in reached for a in op.pre)]
        for op in ready:
            reached.update(op.add)
    lost = {id(op) for op in pending}
    return [op for op in ops if id(op) not in lost]


def prune(
    ops: Sequence[GroundOp],
    inits: Sequence[tuple[frozenset[str], frozenset[str]]],
    init: Iterable[Atom],
) -> list[GroundOp]:
    """The ops that remain possible (module docstring); `inits` are (fluent atoms, symbols)
    per scene, `init` the union problem's initial atoms."""
    groups = _exclusive_groups(ops, inits)
    return _reachable([op for op in ops if _possible(op, groups)], init)
