"""Relaxed-reachability grounding: the ground actions a planner can ever apply.

Starting from the initial atoms, every action schema is instantiated by a join over
its positive preconditions (static and so-far reachable fluent atoms, most-bound
literal first, with per-argument indexes); static negative literals and equalities
are checked exactly, fluent negative literals are relaxed (assumed achievable). The
add effects of new actions extend the reachable set until a fixpoint. Conditional effects
have static conditions, so each ground action's are resolved against the initial state and
become plain add and delete effects. This is what
Fast Downward's translator computes, specialised to our STRIPS subset and fast
enough to run on every planning call.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl import Action, Atom, Domain, Literal, Problem

Tuple = tuple[str, ...]


@dataclass(frozen=True)
class GroundOp:
    """A ground action: name with arguments, fluent conditions and effects."""

    name: str  # "pick-support a b c"
    pre: tuple[Atom, ...]
    pre_neg: tuple[Atom, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]


class _Index:
    """Atoms of one predicate with lookup by (position, value)."""

    def __init__(self) -> None:
        self.tuples: set[Tuple] = set()
        self.by: dict[tuple[int, str], list[Tuple]] = defaultdict(list)
        self.values: dict[int, set[str]] = defaultdict(set)

    def add(self, args: Tuple) -> bool:
        if args in self.tuples:
            return False
        self.tuples.add(args)
        for i, v in enumerate(args):
            self.by[(i, v)].append(args)
            self.values[i].add(v)
        return True

    def candidates(self, pattern: list[str | None]) -> list[Tuple] | set[Tuple]:
        best: list[Tuple] | set[Tuple] = self.tuples
        for i, v in enumerate(pattern):
            if v is not None:
                lst = self.by.get((i, v), [])
                if len(lst) < len(best):
                    best = lst
        return best


@dataclass
class _Schema:
    action: Action
    params: tuple[str, ...]
    positive: tuple[Atom, ...]
    checks: tuple[Literal, ...]  # static negatives and (in)equalities, checked when bound
    types: Mapping[str, str]
    fluent_positions: tuple[int, ...]  # indexes into `positive` of fluent literals


@dataclass(frozen=True)
class _Step:
    atom: Atom
    use_delta: bool
    checks: tuple[Literal, ...]  # checks whose variables are all bound after this step
    args: tuple[tuple[str, bool], ...]  # (argument, is it a variable), precomputed for `_join`


def _estimate(atom: Atom, bound: set[str], atoms: Mapping[str, _Index]) -> float:
    """Expected number of matches of `atom` once the variables in `bound` are fixed."""
    idx = atoms.get(atom.predicate)
    if idx is None or not idx.tuples:
        return 0.0
    best = float(len(idx.tuples))
    for i, a in enumerate(atom.args):
        if a[0] != "?":
            best = min(best, float(len(idx.by.get((i, a), ()))))
        elif a in bound:
            best = min(best, len(idx.tuples) / (len(idx.values[i]) or 1))
    return best


def _plan(
    schema: _Schema, seed: int | None, atoms: Mapping[str, _Index]
) -> tuple[list[_Step], tuple[Literal, ...]]:
    """A fixed join order: the seed (delta) literal first, then the most selective literal."""
    remaining = list(range(len(schema.positive)))
    order: list[int] = []
    bound: set[str] = set()
    if seed is not None:
        order.append(seed)
        remaining.remove(seed)
        bound |= {a for a in schema.positive[seed].args if a.startswith("?")}
    while remaining:
        best = min(remaining, key=lambda i: _estimate(schema.positive[i], bound, atoms))
        order.append(best)
        remaining.remove(best)
        bound |= {a for a in schema.positive[best].args if a.startswith("?")}
    steps, done = [], set()
    bound = set()
    for i in order:
        bound |= {a for a in schema.positive[i].args if a.startswith("?")}
        ready = tuple(
            c
            for c in schema.checks
            if c not in done and all(a in bound or not a.startswith("?") for a in c.atom.args)
        )
        done |= set(ready)
        atom = schema.positive[i]
        args = tuple((a, a[0] == "?") for a in atom.args)
        steps.append(_Step(atom, i == seed, ready, args))
    return steps, tuple(c for c in schema.checks if c not in done)


def _holds_static(lit: Literal, binding: Mapping[str, str], static: Mapping[str, _Index]) -> bool:
    args = tuple(binding.get(a, a) for a in lit.atom.args)
    if lit.atom.predicate == "=":
        value = args[0] == args[1]
    else:
        idx = static.get(lit.atom.predicate)
        value = idx is not None and args in idx.tuples
    return value == lit.positive


def _join(
    schema: _Schema,
    steps: list[_Step],
    late: tuple[Literal, ...],
    atoms: Mapping[str, _Index],
    delta: Mapping[str, _Index],
    static: Mapping[str, _Index],
    objects_of: Mapping[str, list[str]],
) -> Iterator[dict[str, str]]:
    """Bindings satisfying the positive preconditions (the seed step over `delta`) and checks."""
    binding: dict[str, str] = {}

    def rec(k: int) -> Iterator[dict[str, str]]:
        if k == len(steps):
            free = [p for p in schema.params if p not in binding]
            if free:
                var = free[0]
                for obj in objects_of[schema.types[var]]:
                    binding[var] = obj
                    yield from rec(k)
                    del binding[var]
                return
            if all(_holds_static(c, binding, static) for c in late):
                yield dict(binding)
            return
        step = steps[k]
        idx = (delta if step.use_delta else atoms).get(step.atom.predicate)
        if idx is None:
            return
        args, checks = step.args, step.checks
        pattern = [binding.get(a) if var else a for a, var in args]
        if None not in pattern:  # fully bound: a membership test
            if tuple(pattern) in idx.tuples and all(
                _holds_static(c, binding, static) for c in checks
            ):
                yield from rec(k + 1)
            return
        for tup in list(idx.candidates(pattern)):
            added = []
            ok = True
            for (a, var), v in zip(args, tup, strict=True):
                if var:
                    cur = binding.get(a)
                    if cur is None:
                        binding[a] = v
                        added.append(a)
                    elif cur != v:
                        ok = False
                        break
                elif a != v:
                    ok = False
                    break
            if ok and (not checks or all(_holds_static(c, binding, static) for c in checks)):
                yield from rec(k + 1)
            for a in added:
                del binding[a]

    yield from rec(0)


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


def reachable_ops(
    domain: Domain, problem: Problem
) -> tuple[list[GroundOp], set[Atom], frozenset[str]]:
    """Ground actions reachable under delete relaxation, all reachable atoms, static predicates."""
    check_problem_atoms(domain, problem)
    fluent = domain.fluent_predicates()
    objects_of: dict[str, list[str]] = defaultdict(list)
    for name, typ in (*domain.constants.items(), *problem.objects.items()):
        t: str | None = typ
        while t is not None:
            objects_of[t].append(name)
            t = domain.types.get(t)
    for t in domain.types:
        objects_of.setdefault(t, [])
    objects_of.setdefault("object", [n for n in (*domain.constants, *problem.objects)])

    conditions = domain.condition_predicates()
    cond_facts = frozenset(a for a in problem.init if a.predicate in conditions)
    atoms: dict[str, _Index] = defaultdict(_Index)
    static: dict[str, _Index] = defaultdict(_Index)
    for a in problem.init:
        atoms[a.predicate].add(a.args)
        if a.predicate not in fluent:
            static[a.predicate].add(a.args)
    schemas = []
    for act in domain.actions.values():
        positive = tuple(
            lit.atom for lit in act.precondition if lit.positive and lit.atom.predicate != "="
        )
        checks = tuple(
            lit
            for lit in act.precondition
            if lit.atom.predicate == "=" or (not lit.positive and lit.atom.predicate not in fluent)
        )
        schemas.append(
            _Schema(
                act,
                tuple(v for v, _ in act.parameters),
                positive,
                checks,
                dict(act.parameters),
                tuple(i for i, a in enumerate(positive) if a.predicate in fluent),
            )
        )

    plans: dict[tuple[int, int | None], tuple[list[_Step], tuple[Literal, ...]]] = {}
    ops: dict[str, GroundOp] = {}
    delta: dict[str, _Index] | None = None  # None: first round, join over everything
    while delta is None or delta:
        new: dict[str, _Index] = defaultdict(_Index)
        for schema in schemas:
            act = schema.action
            seeds = (None,) if delta is None else schema.fluent_positions
            for seed in seeds:
                if seed is not None and schema.positive[seed].predicate not in delta:
                    continue
                key = (id(schema), seed)
                if key not in plans:  # join order from the statistics when first needed
                    plans[key] = _plan(schema, seed, atoms)
                steps, late = plans[key]
                for binding in list(
                    _join(schema, steps, late, atoms, delta or {}, static, objects_of)
                ):
                    args = tuple(binding[p] for p in schema.params)
                    name = " ".join((act.name, *args))
                    if name in ops:
                        continue
                    pre, add, dele = act.instantiate(args, cond_facts)
                    ops[name] = GroundOp(
                        name,
                        tuple(
                            lit.atom for lit in pre if lit.positive and lit.atom.predicate in fluent
                        ),
                        tuple(
                            lit.atom
                            for lit in pre
                            if not lit.positive and lit.atom.predicate in fluent
                        ),
                        add,
                        dele,
                    )
                    for a in add:
                        if a.args not in atoms[a.predicate].tuples:
                            new[a.predicate].add(a.args)
        for pred, idx in new.items():
            for args in idx.tuples:
                atoms[pred].add(args)
        delta = dict(new)
    reached = {Atom(p, args) for p, idx in atoms.items() for args in idx.tuples}
    return (
        sorted(ops.values(), key=lambda o: o.name),
        reached,
        frozenset(p for p in domain.predicates if p not in fluent),
    )
