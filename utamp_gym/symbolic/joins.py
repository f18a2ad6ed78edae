"""Conjunctive joins over atom tables: what the grounder (`symbolic.reach`) enumerates.

`Index` holds the atoms of one predicate with hash tables keyed by the values at some
positions; `join_plan` fixes the order in which a `Join`'s literals are matched from their
shapes alone (so one order serves every task of a domain), and `run_join` enumerates the
bindings that satisfy it against the tables of one task, checking a `Deadline` as it goes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import lru_cache
from operator import itemgetter
from typing import NamedTuple

from utamp_gym.deadline import Deadline
from utamp_gym.symbolic.pddl import Atom, Literal

Tuple = tuple[str, ...]
_CHECK_EVERY = 255  # join steps between two deadline checks (a mask: 2**k - 1)


Key = object  # a table key: () for no variable, the value for one, a tuple for several


class Index:
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


def variables(atom: Atom) -> list[str]:
    return [a for a in atom.args if a[0] == "?"]


class Join(NamedTuple):
    """A conjunction to enumerate: positive atoms, checks tested once their variables are bound
    (static negative literals, equalities) and the variables of each result."""

    positive: tuple[Atom, ...]
    checks: tuple[Literal, ...]
    variables: tuple[str, ...]


class Step(NamedTuple):
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


JoinPlan = tuple[tuple[Step, ...], tuple[Literal, ...], tuple[str, ...]]  # steps, late, unbound


@lru_cache(maxsize=4096)
def join_plan(join: Join, seed: int | None) -> JoinPlan:
    """A fixed join order from the literals' shapes alone (no statistics, so one order
    serves every task of the domain): the seed (delta) literal first; then a literal whose
    variables are all bound (a membership test), else a static group relation sharing a bound
    variable (an exact filter), else the literal with the smallest share of free arguments
    (then the fewest; static relations first). A pure function of hashable data, remembered
    per process: every grounder of a domain shares its orders."""
    positive = join.positive
    var_sets = [frozenset(variables(a)) for a in positive]
    # the score's parts, kept up to date as variables are bound: arguments known (constants
    # and bound variables, repeats counted), distinct variables still free
    known = [sum(1 for a in atom.args if a[0] != "?") for atom in positive]
    free = [len(vs) for vs in var_sets]
    arity = [len(atom.args) or 1 for atom in positive]
    not_group = [atom.predicate[0] != "#" for atom in positive]
    occurs: dict[str, list[int]] = {}  # variable -> the literals it is an argument of
    for i, atom in enumerate(positive):
        for a in atom.args:
            if a[0] == "?":
                occurs.setdefault(a, []).append(i)
    remaining = list(range(len(positive)))
    order: list[int] = []
    bound: set[str] = set()

    def bind(i: int) -> None:
        order.append(i)
        remaining.remove(i)
        for v in var_sets[i] - bound:
            bound.add(v)
            hits = occurs[v]
            for j in hits:
                known[j] += 1
            for j in set(hits):
                free[j] -= 1

    if seed is not None:
        bind(seed)
    while remaining:
        pool = [i for i in remaining if not free[i]]
        if not pool:
            pool = [i for i in remaining if not not_group[i] and var_sets[i] & bound]
        # the first of the smallest (share of arguments unknown, free variables, not a group)
        bind(min(pool or remaining, key=lambda i: (1 - known[i] / arity[i], free[i], not_group[i])))
    checks = [(c, frozenset(variables(c.atom))) for c in join.checks]
    steps, done = [], set()
    bound = set()
    for i in order:
        atom = positive[i]
        args = atom.args
        consts = tuple((k, a) for k, a in enumerate(args) if a[0] != "?")
        known = [(k, a) for k, a in enumerate(args) if a in bound]
        first: dict[str, int] = {}
        free, repeats = [], []
        for k, a in enumerate(args):
            if a[0] != "?" or a in bound:
                continue
            if a in first:
                repeats.append((first[a], k))
            else:
                first[a] = k
                free.append((k, a))
        bound |= var_sets[i]
        ready = tuple(c for c, vs in checks if vs <= bound and c not in done)
        done.update(ready)
        getter = itemgetter(*(a for _, a in known)) if known else None
        steps.append(
            Step(
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


def holds_static(lit: Literal, binding: Mapping[str, str], static: Mapping[str, Index]) -> bool:
    args = tuple(binding.get(a, a) for a in lit.atom.args)
    if lit.atom.predicate == "=":
        value = args[0] == args[1]
    else:
        idx = static.get(lit.atom.predicate)
        value = idx is not None and args in idx.tuples
    return value == lit.positive


class Context:
    """What one grounding call joins against, and its deadline."""

    def __init__(
        self,
        static: Mapping[str, Index],
        objects_of: Mapping[str, list[str]],
        deadline: Deadline | None,
    ):
        self.static, self.objects_of, self.deadline = static, objects_of, deadline


def run_join(
    plan: JoinPlan,
    types: Mapping[str, str],
    ctx: Context,
    atoms: Mapping[str, Index],
    delta: Mapping[str, Index],
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
        elif not late or all(holds_static(c, binding, static) for c in late):
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
            if checks and not all(holds_static(c, binding, static) for c in checks):
                continue
            rec(k + 1)
        for _, var in free:
            del binding[var]

    rec(0)
    return out


__all__ = [
    "Context",
    "Index",
    "Join",
    "JoinPlan",
    "Key",
    "Step",
    "holds_static",
    "join_plan",
    "run_join",
    "variables",
]
