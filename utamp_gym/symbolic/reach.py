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
they are computed once per process and kept between calls. `Grounder` grounds tasks of one
domain; `reachable_ops` grounds once with a fresh grounder. A `Deadline` is checked inside
the joins.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Mapping
from functools import lru_cache
from operator import itemgetter
from typing import NamedTuple

from utamp_gym.deadline import Deadline
from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl import Action, Atom, Domain, Literal, Problem

Tuple = tuple[str, ...]
_CHECK_EVERY = 255  # join steps between two deadline checks (a mask: 2**k - 1)
_CHECK_OPS = 31  # ground operators between two deadline checks (a mask: 2**k - 1)


class GroundOp(NamedTuple):
    """A ground action: name with arguments, fluent conditions and effects."""

    name: str  # "pick-support a b c"
    pre: tuple[Atom, ...]
    pre_neg: tuple[Atom, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]


Key = object  # a table key: () for no variable, the value for one, a tuple for several


class _Index:
    """Atoms of one predicate (argument tuples) with hash tables for lookups: a table holds
    the tuples with given constants at some positions, keyed by the values at others. Tables
    are built on first use and kept up to date as tuples are added."""

    def __init__(self) -> None:
        self.tuples: set[Tuple] = set()
        self._tables: dict[tuple[object, ...], dict[Key, list[Tuple]]] = {}
        self._specs: list[tuple[tuple[tuple[int, str], ...], Callable | None, dict]] = []

    def add(self, args: Tuple) -> bool:
        if args in self.tuples:
            return False
        self.tuples.add(args)
        for consts, getter, table in self._specs:
            for p, v in consts:
                if args[p] != v:
                    break
            else:
                table.setdefault(() if getter is None else getter(args), []).append(args)
        return True

    def lookup(
        self, consts: tuple[tuple[int, str], ...], positions: tuple[int, ...]
    ) -> dict[Key, list[Tuple]]:
        """The tuples with `consts` (position, value), keyed by their values at `positions`."""
        spec = (consts, positions)
        table = self._tables.get(spec)
        if table is None:
            table = self._tables[spec] = {}
            getter = itemgetter(*positions) if positions else None
            self._specs.append((consts, getter, table))
            for args in self.tuples:
                for p, v in consts:
                    if args[p] != v:
                        break
                else:
                    table.setdefault(() if getter is None else getter(args), []).append(args)
        return table


def _variables(atom: Atom) -> list[str]:
    return [a for a in atom.args if a[0] == "?"]


class _Join(NamedTuple):
    """A conjunction to enumerate: positive atoms, checks tested once their variables are bound
    (static negative literals, equalities) and the variables of each result."""

    positive: tuple[Atom, ...]
    checks: tuple[Literal, ...]
    variables: tuple[str, ...]


class _Group(NamedTuple):
    """Connected positive static literals of a schema, joined once per task into the relation
    of the synthetic atom `atom` (predicate ``#action/k``, its variables as arguments)."""

    join: _Join
    atom: Atom


class _Schema(NamedTuple):
    action: Action
    types: Mapping[str, str]
    groups: tuple[_Group, ...]
    main: _Join  # group atoms, then positive fluent literals; variables = the parameters
    fluent_positions: tuple[int, ...]  # indexes into `main.positive` of fluent literals
    pre: tuple[Atom, ...]  # positive fluent preconditions (templates)
    pre_neg: tuple[Atom, ...]  # negative fluent preconditions (templates)


class _Step(NamedTuple):
    """One literal of a join plan: look its tuples up in the table of its constants keyed by
    the variables bound earlier (`getter` reads them from the binding) and bind the new
    variables (`free`)."""

    atom: Atom
    use_delta: bool
    checks: tuple[Literal, ...]  # checks whose variables are all bound after this step
    consts: tuple[tuple[int, str], ...]  # (position, constant)
    positions: tuple[int, ...]  # positions of variables bound before this step
    getter: Callable[[Mapping[str, str]], Key] | None  # their values from the binding
    free: tuple[tuple[int, str], ...]  # (position, variable) first bound here
    repeats: tuple[tuple[int, int], ...]  # positions that must hold equal values (?x ... ?x)


Plan = tuple[tuple[_Step, ...], tuple[Literal, ...], tuple[str, ...]]  # steps, late, unbound


@lru_cache(maxsize=4096)
def _plan(join: _Join, seed: int | None) -> Plan:
    """A fixed join order from the literals' shapes alone (no statistics, so one order
    serves every task of the domain): the seed (delta) literal first; then a literal whose
    variables are all bound (a membership test), else a static group relation sharing a bound
    variable (an exact filter), else the literal with the smallest share of free arguments
    (then the fewest; static relations first). A pure function of hashable data, remembered
    per process: every grounder of a domain shares its orders."""
    shapes = [
        (frozenset(_variables(a)), a.predicate[0] == "#", len(a.args), a) for a in join.positive
    ]
    remaining = list(range(len(join.positive)))
    order: list[int] = []
    bound: set[str] = set()

    def score(i: int) -> tuple[float, int, bool]:
        variables, is_group, arity, atom = shapes[i]
        free = len(variables - bound)
        known = sum(1 for a in atom.args if a[0] != "?" or a in bound)
        return 1.0 - known / (arity or 1), free, not is_group

    if seed is not None:
        order.append(seed)
        remaining.remove(seed)
        bound |= shapes[seed][0]
    while remaining:
        tests = [i for i in remaining if shapes[i][0] <= bound]
        connected = [i for i in remaining if shapes[i][1] and shapes[i][0] & bound]
        best = min(tests or connected or remaining, key=score)
        order.append(best)
        remaining.remove(best)
        bound |= shapes[best][0]
    steps, done = [], set()
    bound = set()
    for i in order:
        atom = join.positive[i]
        consts = tuple((k, a) for k, a in enumerate(atom.args) if a[0] != "?")
        known = [(k, a) for k, a in enumerate(atom.args) if a in bound]
        first: dict[str, int] = {}
        free, repeats = [], []
        for k, a in enumerate(atom.args):
            if a[0] != "?" or a in bound:
                continue
            if a in first:
                repeats.append((first[a], k))
            else:
                first[a] = k
                free.append((k, a))
        bound |= set(_variables(atom))
        ready = tuple(
            c
            for c in join.checks
            if c not in done and all(a in bound or a[0] != "?" for a in c.atom.args)
        )
        done |= set(ready)
        getter = itemgetter(*(a for _, a in known)) if known else None
        steps.append(
            _Step(
                atom,
                i == seed,
                ready,
                consts,
                tuple(k for k, _ in known),
                getter,
                tuple(free),
                tuple(repeats),
            )
        )
    late = tuple(c for c in join.checks if c not in done)
    return tuple(steps), late, tuple(v for v in join.variables if v not in bound)


def _holds_static(lit: Literal, binding: Mapping[str, str], static: Mapping[str, _Index]) -> bool:
    args = tuple(binding.get(a, a) for a in lit.atom.args)
    if lit.atom.predicate == "=":
        value = args[0] == args[1]
    else:
        idx = static.get(lit.atom.predicate)
        value = idx is not None and args in idx.tuples
    return value == lit.positive


class _Context:
    """What one grounding call joins against, and its deadline."""

    def __init__(
        self,
        static: Mapping[str, _Index],
        objects_of: Mapping[str, list[str]],
        deadline: Deadline | None,
    ):
        self.static, self.objects_of, self.deadline = static, objects_of, deadline


def _join(
    plan: Plan,
    types: Mapping[str, str],
    ctx: _Context,
    atoms: Mapping[str, _Index],
    delta: Mapping[str, _Index],
) -> list[dict[str, str]]:
    """Bindings satisfying the positive atoms (the seed step over `delta`) and the checks;
    variables no atom binds range over the objects of their type."""
    steps, late, unbound = plan
    static, deadline = ctx.static, ctx.deadline
    binding: dict[str, str] = {}
    out: list[dict[str, str]] = []
    sources = []
    for step in steps:
        idx = (delta if step.use_delta else atoms).get(step.atom.predicate)
        if idx is None:
            return out
        sources.append(idx)
    tables: list[dict[Key, list[Tuple]] | None] = [None] * len(steps)  # fetched when reached
    n_steps, ticks = len(steps), 0

    def finish(j: int) -> None:
        if j < len(unbound):
            var = unbound[j]
            for obj in ctx.objects_of[types[var]]:
                binding[var] = obj
                finish(j + 1)
            binding.pop(var, None)
        elif not late or all(_holds_static(c, binding, static) for c in late):
            out.append(dict(binding))

    def rec(k: int) -> None:
        nonlocal ticks
        if k == n_steps:
            finish(0)
            return
        ticks += 1
        if deadline is not None and not ticks & _CHECK_EVERY:
            deadline.check("grounding")
        step = steps[k]
        table = tables[k]
        if table is None:
            table = tables[k] = sources[k].lookup(step.consts, step.positions)
        getter = step.getter
        matches = table.get(() if getter is None else getter(binding))
        if not matches:
            return
        free, repeats, checks = step.free, step.repeats, step.checks
        for tup in matches:
            for pos, var in free:
                binding[var] = tup[pos]
            if repeats and any(tup[a] != tup[b] for a, b in repeats):
                continue
            if checks and not all(_holds_static(c, binding, static) for c in checks):
                continue
            rec(k + 1)
        for _, var in free:
            del binding[var]

    rec(0)
    return out


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
        vs = set(_variables(atom))
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
        mine = [c for c in left if set(_variables(c.atom)) and set(_variables(c.atom)) <= vs]
        left = [c for c in left if c not in mine]
        order = tuple(dict.fromkeys(v for a in lits for v in _variables(a)))
        join = _Join(tuple(lits), tuple(mine), order)
        groups.append(_Group(join, Atom(f"#{action.name}/{k}", order)))
    fluent_pos = [lit.atom for lit in pre if lit.positive and lit.atom.predicate in fluent]
    main = _Join(
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
        self._group_plans = tuple(
            tuple(_plan(g.join, None) for g in schema.groups) for schema in self._schemas
        )
        self._main_plans = tuple(
            {seed: _plan(schema.main, seed) for seed in (None, *schema.fluent_positions)}
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

        atoms: dict[str, _Index] = defaultdict(_Index)  # fluent atoms and group relations
        static: dict[str, _Index] = defaultdict(_Index)
        for a in problem.init:
            (static if a.predicate not in fluent else atoms)[a.predicate].add(a.args)
        cond_facts = frozenset(a for a in problem.init if a.predicate in self._conditions)
        ctx = _Context(static, objects_of, deadline)

        live = []  # schemas whose static groups are all non-empty
        for s, schema in enumerate(self._schemas):
            for g, group in enumerate(schema.groups):
                plan = self._group_plans[s][g]
                rel = atoms[group.atom.predicate] = _Index()
                for b in _join(plan, schema.types, ctx, static, {}):
                    rel.add(tuple(b[v] for v in group.join.variables))
                if not rel.tuples:
                    break
            else:
                live.append((s, schema))

        ops: dict[str, GroundOp] = {}
        delta: dict[str, _Index] | None = None  # None: first round, join over everything
        while delta is None or delta:
            new: dict[str, _Index] = defaultdict(_Index)
            for s, schema in live:
                act = schema.action
                for seed in (None,) if delta is None else schema.fluent_positions:
                    if seed is not None and schema.main.positive[seed].predicate not in delta:
                        continue
                    plan = self._main_plans[s][seed]
                    for b in _join(plan, schema.types, ctx, atoms, delta or {}):
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
