"""Relaxed-reachability grounding: the ground actions a planner can ever apply.

Static preconditions are joined first. Per action schema, the positive static literals are
split into groups connected by shared variables; each group is joined once per task (with
the static negative literals and equalities over its variables) into one relation, which
then acts as a single, very selective literal. Starting from the initial atoms, each schema
is instantiated by a join over these relations and its positive fluent preconditions (seed
literal first, then the most selective one, with per-argument indexes); fluent negative
literals are relaxed (assumed achievable). The add effects of new actions extend the
reachable set until a fixpoint; each round joins only with at least one new atom
(semi-naive). Conditional effects have static conditions, so each ground action's are
resolved against the initial state and become plain add and delete effects. This is what
Fast Downward's translator computes, specialised to our subset and fast enough to run on
every planning call.

Join orders come from the shapes of the literals alone (so one order suits every task);
they are worked out once per domain and kept on disk (`symbolic.join_store`). `Grounder`
grounds tasks of one domain; `reachable_ops` grounds once with a fresh grounder. A
`Deadline` is checked inside the joins (`symbolic.joins`).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Mapping
from typing import NamedTuple

from utamp_gym.deadline import Deadline
from utamp_gym.errors import PddlError
from utamp_gym.symbolic.join_store import join_plans
from utamp_gym.symbolic.joins import Context, Index, Join, run_join, variables
from utamp_gym.symbolic.pddl import Action, Atom, Domain, Problem

_CHECK_OPS = 31  # ground operators between two deadline checks (a mask: 2**k - 1)


class GroundOp(NamedTuple):
    """A ground action: name with arguments, fluent conditions and effects."""

    name: str  # "pick-support a b c"
    pre: tuple[Atom, ...]
    pre_neg: tuple[Atom, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]


class _Group(NamedTuple):
    """Connected positive static literals of a schema, joined once per task into the relation
    of the synthetic atom `atom` (predicate ``#action/k``, its variables as arguments)."""

    join: Join
    atom: Atom


class _Schema(NamedTuple):
    action: Action
    types: Mapping[str, str]
    groups: tuple[_Group, ...]
    main: Join  # group atoms, then positive fluent literals; variables = the parameters
    fluent_positions: tuple[int, ...]  # indexes into `main.positive` of fluent literals
    pre: tuple[Atom, ...]  # positive fluent preconditions (templates)
    pre_neg: tuple[Atom, ...]  # negative fluent preconditions (templates)


def check_problem_atoms(domain: Domain, problem: Problem) -> None:
    """Reject init/goal atoms with an unknown predicate or object, or a wrong arity."""
    known = {*domain.constants, *problem.objects}
    atoms = [("init", a) for a in problem.init] + [("goal", lit.atom) for lit in problem.goal]
    for where, a in atoms:
        if a.predicate == "=":
            continue
        if a.predicate not in domain.predicates:
            raise PddlError(f"{problem.source}: {where} uses unknown predicate '{a.predicate}'")
        if len(a.args) != len(domain.predicates[a.predicate]):
            raise PddlError(f"{problem.source}: {where} atom {a} has the wrong number of arguments")
        unknown = [x for x in a.args if x not in known]
        if unknown:
            where = f"{problem.source}: {where} atom {a}"
            raise PddlError(f"{where} uses unknown object {unknown[0]!r}")


def _schema(action: Action, fluent: frozenset[str]) -> _Schema:
    """Split an action's precondition into static groups, fluent literals and checks."""
    pre = action.precondition
    static = [
        lit.atom
        for lit in pre
        if lit.positive and lit.atom.predicate != "=" and lit.atom.predicate not in fluent
    ]
    checks = [
        lit
        for lit in pre
        if lit.atom.predicate == "=" or (not lit.positive and lit.atom.predicate not in fluent)
    ]
    # connected components of the static literals (literals sharing a variable)
    components: list[tuple[list[Atom], set[str]]] = []
    for atom in static:
        vs = set(variables(atom))
        touching = [c for c in components if c[1] & vs]
        merged = ([atom], set(vs))
        for c in touching:
            merged[0][:0] = c[0]
            merged[1].update(c[1])
            components.remove(c)
        components.append(merged)
    groups = []
    left = list(checks)
    for k, (lits, vs) in enumerate(components):
        mine = [c for c in left if set(variables(c.atom)) and set(variables(c.atom)) <= vs]
        left = [c for c in left if c not in mine]
        order = tuple(dict.fromkeys(v for a in lits for v in variables(a)))
        join = Join(tuple(lits), tuple(mine), order)
        groups.append(_Group(join, Atom(f"#{action.name}/{k}", order)))
    fluent_pos = [lit.atom for lit in pre if lit.positive and lit.atom.predicate in fluent]
    main = Join(
        (*(g.atom for g in groups), *fluent_pos),
        tuple(left),
        tuple(v for v, _ in action.parameters),
    )
    return _Schema(
        action,
        dict(action.parameters),
        tuple(groups),
        main,
        tuple(range(len(groups), len(main.positive))),
        tuple(fluent_pos),
        tuple(lit.atom for lit in pre if not lit.positive and lit.atom.predicate in fluent),
    )


_new_atom = tuple.__new__  # builds an Atom without its Python-level __new__


def _sub(atom: Atom, binding: Mapping[str, str]) -> Atom:
    return _new_atom(Atom, (atom.predicate, tuple(map(binding.get, atom.args, atom.args))))


class Grounder:
    """Relaxed-reachability grounding for one domain; keeps join orders between calls."""

    def __init__(self, domain: Domain) -> None:
        self.domain = domain
        self.fluent = domain.fluent_predicates()
        self.static_predicates = frozenset(p for p in domain.predicates if p not in self.fluent)
        self._conditions = domain.condition_predicates()
        self._schemas = tuple(_schema(a, self.fluent) for a in domain.actions.values())
        # join orders, computed once: per schema, one per static group and one per seed
        wanted = [
            *((g.join, None) for schema in self._schemas for g in schema.groups),
            *((s.main, seed) for s in self._schemas for seed in (None, *s.fluent_positions)),
        ]
        plans = iter(join_plans(wanted))  # in the order of `wanted`
        self._group_plans = tuple(
            tuple(next(plans) for _ in schema.groups) for schema in self._schemas
        )
        self._main_plans = tuple(
            {seed: next(plans) for seed in (None, *schema.fluent_positions)}
            for schema in self._schemas
        )

    def ground(
        self, problem: Problem, deadline: Deadline | None = None
    ) -> tuple[list[GroundOp], set[Atom]]:
        """Ground actions reachable under delete relaxation (sorted by name), reachable atoms.

        Raises `PddlError` for unknown predicates or objects and `PlanningTimeout` (phase
        ``grounding``) once `deadline` passes.
        """
        domain, fluent = self.domain, self.fluent
        check_problem_atoms(domain, problem)
        objects_of: dict[str, list[str]] = defaultdict(list)
        for name, typ in (*domain.constants.items(), *problem.objects.items()):
            t: str | None = typ
            while t is not None:
                objects_of[t].append(name)
                t = domain.types.get(t)
        for t in domain.types:
            objects_of.setdefault(t, [])
        objects_of.setdefault("object", [n for n in (*domain.constants, *problem.objects)])

        atoms: dict[str, Index] = defaultdict(Index)  # fluent atoms and group relations
        static: dict[str, Index] = defaultdict(Index)
        for a in problem.init:
            (static if a.predicate not in fluent else atoms)[a.predicate].add(a.args)
        cond_facts = frozenset(a for a in problem.init if a.predicate in self._conditions)
        ctx = Context(static, objects_of, deadline)

        live = []  # schemas whose static groups are all non-empty
        for s, schema in enumerate(self._schemas):
            for g, group in enumerate(schema.groups):
                plan = self._group_plans[s][g]
                rel = atoms[group.atom.predicate] = Index()
                for b in run_join(plan, schema.types, ctx, static, {}):
                    rel.add(tuple(b[v] for v in group.join.variables))
                if not rel.tuples:
                    break
            else:
                live.append((s, schema))

        ops: dict[str, GroundOp] = {}
        delta: dict[str, Index] | None = None  # None: first round, join over everything
        while delta is None or delta:
            new: dict[str, Index] = defaultdict(Index)
            for s, schema in live:
                act = schema.action
                for seed in (None,) if delta is None else schema.fluent_positions:
                    if seed is not None and schema.main.positive[seed].predicate not in delta:
                        continue
                    plan = self._main_plans[s][seed]
                    for b in run_join(plan, schema.types, ctx, atoms, delta or {}):
                        name = " ".join((act.name, *map(b.__getitem__, schema.main.variables)))
                        if name in ops:
                            continue
                        add, dele = act.effects(b, cond_facts)
                        ops[name] = GroundOp(
                            name,
                            tuple(_sub(a, b) for a in schema.pre),
                            tuple(_sub(a, b) for a in schema.pre_neg),
                            add,
                            dele,
                        )
                        for a in add:
                            if a.args not in atoms[a.predicate].tuples:
                                new[a.predicate].add(a.args)
                        if deadline is not None and not len(ops) & _CHECK_OPS:
                            deadline.check("grounding")  # effects can be costly (forall/when)
            if deadline is not None:
                deadline.check("grounding")
            for pred, idx in new.items():
                for args in idx.tuples:
                    atoms[pred].add(args)
            delta = dict(new)
        reached = set(problem.init)
        reached.update(
            Atom(p, args) for p, idx in atoms.items() if p[0] != "#" for args in idx.tuples
        )
        return sorted(ops.values(), key=lambda o: o.name), reached


def reachable_ops(
    domain: Domain, problem: Problem, deadline: Deadline | None = None
) -> tuple[list[GroundOp], set[Atom], frozenset[str]]:
    """Ground actions reachable under delete relaxation, all reachable atoms, static predicates."""
    grounder = Grounder(domain)
    ops, reached = grounder.ground(problem, deadline)
    return ops, reached, grounder.static_predicates


__all__ = ["GroundOp", "Grounder", "check_problem_atoms", "reachable_ops"]
