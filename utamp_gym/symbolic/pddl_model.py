"""The parsed form of a PDDL task: atoms, literals, actions, domains and problems.

Plain frozen data, produced by `utamp_gym.symbolic.pddl` and read by the validator,
the grounder, the SAS writer and the envs. Names are lower-case.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Iterator, Mapping
from types import MappingProxyType
from typing import NamedTuple


class Atom(NamedTuple):
    """A predicate applied to arguments (variables ``?x``, constants or objects).

    A named tuple: grounding hashes and compares atoms millions of times, and tuples do that
    in C (an `Atom` equals the plain tuple ``(predicate, args)``).
    """

    predicate: str
    args: tuple[str, ...] = ()

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.args)) + ")"


class Literal(NamedTuple):
    """An atom or its negation; predicate ``=`` means equality of its two arguments."""

    atom: Atom
    positive: bool = True

    def __str__(self) -> str:
        return str(self.atom) if self.positive else f"(not {self.atom})"


_NO_SPELLING: Mapping[str, str] = MappingProxyType({})


def _sub(a: Atom, sub: Mapping[str, str]) -> Atom:
    return tuple.__new__(Atom, (a.predicate, tuple(map(sub.get, a.args, a.args))))


def _holds(lit: Literal, facts: Collection[Atom]) -> bool:
    atom = lit.atom
    true = atom.args[0] == atom.args[1] if atom.predicate == "=" else atom in facts
    return true == lit.positive


class CondEffect(NamedTuple):
    """``(forall (?v - t ...) (when (and cond ...) (and eff ...)))`` in an action's effect.

    For every binding of `variables` under which all `condition` literals hold, the atoms of
    `add` become true and those of `delete` false. The parser guarantees that conditions use
    static predicates only and that every variable occurs in a positive condition literal at an
    argument of its type, so the bindings are found by matching those literals against the
    task's static atoms (`bindings`); a ``when`` without ``forall`` has no variables.
    """

    variables: tuple[tuple[str, str], ...]  # (?var, type)
    condition: tuple[Literal, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]

    def bindings(self, sub: Mapping[str, str], facts: Collection[Atom]) -> Iterator[dict[str, str]]:
        """Extensions of `sub` (action parameters -> objects) satisfying the condition."""
        wanted = {v for v, _ in self.variables}
        positive = [
            lit.atom
            for lit in self.condition
            if lit.positive and lit.atom.predicate != "=" and wanted & set(lit.atom.args)
        ]
        by_pred: dict[str, list[tuple[str, ...]]] = {a.predicate: [] for a in positive}
        if by_pred:
            for f in facts:
                if f.predicate in by_pred:
                    by_pred[f.predicate].append(f.args)

        def rec(k: int, binding: dict[str, str]) -> Iterator[dict[str, str]]:
            if k == len(positive):
                if all(
                    _holds(Literal(_sub(c.atom, binding), c.positive), facts)
                    for c in self.condition
                ):
                    yield dict(binding)
                return
            pattern = [binding.get(x, x) for x in positive[k].args]
            for args in by_pred[positive[k].predicate]:
                new = dict(binding)
                if all(
                    new.setdefault(x, v) == v if x.startswith("?") else x == v
                    for x, v in zip(pattern, args, strict=True)
                ):
                    yield from rec(k + 1, new)

        yield from rec(0, dict(sub))


class Action(NamedTuple):
    """An action schema: typed parameters, precondition literals, add and delete effects.

    `cond_effects` are the conditional effects (`CondEffect`); `instantiate` resolves them
    against the task's static atoms.
    """

    name: str
    parameters: tuple[tuple[str, str], ...]  # (?var, type)
    precondition: tuple[Literal, ...]
    add_effects: tuple[Atom, ...]
    del_effects: tuple[Atom, ...]
    cond_effects: tuple[CondEffect, ...] = ()

    @property
    def arity(self) -> int:
        return len(self.parameters)

    def instantiate(
        self, args: Iterable[str], facts: Collection[Atom] | None = None
    ) -> tuple[tuple[Literal, ...], tuple[Atom, ...], tuple[Atom, ...]]:
        """Substitute `args` for the parameters: (precondition, add effects, delete effects).

        With `facts` (any collection holding the task's static atoms: its initial state or a
        state reached from it), the effects include the conditional effects whose condition
        holds there. Without it they are the unconditional effects only, which is all a caller
        that reads just the precondition needs; a caller that applies the effects of an action
        with `cond_effects` must pass `facts`.
        """
        sub = dict(zip((v for v, _ in self.parameters), args, strict=True))
        pre = tuple(Literal(_sub(lit.atom, sub), lit.positive) for lit in self.precondition)
        return (pre, *self.effects(sub, facts))

    def effects(
        self, sub: Mapping[str, str], facts: Collection[Atom] | None = None
    ) -> tuple[tuple[Atom, ...], tuple[Atom, ...]]:
        """(add, delete) effects under the parameter binding `sub` (see `instantiate`)."""
        add = [_sub(a, sub) for a in self.add_effects]
        dele = [_sub(a, sub) for a in self.del_effects]
        for ce in self.cond_effects if facts is not None else ():
            for binding in ce.bindings(sub, facts):
                add += [_sub(a, binding) for a in ce.add]
                dele += [_sub(a, binding) for a in ce.delete]
        return tuple(dict.fromkeys(add)), tuple(dict.fromkeys(dele))


class Domain(NamedTuple):
    """A parsed domain; mappings are read-only and `types` maps each type to its parent.

    Equality ignores `spelling` and `source` (the same domain read from another file).
    """

    name: str
    requirements: tuple[str, ...]
    types: Mapping[str, str | None]
    constants: Mapping[str, str]  # name -> type
    predicates: Mapping[str, tuple[str, ...]]  # name -> argument types
    actions: Mapping[str, Action]
    spelling: Mapping[str, str] = _NO_SPELLING
    source: str = "<string>"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Domain) and self[:6] == other[:6]

    def __repr__(self) -> str:  # the compared fields only
        shown = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields[:6])
        return f"Domain({shown})"

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = None  # type: ignore[assignment]  # its mappings are not hashable

    def is_subtype(self, sub: str, sup: str) -> bool:
        """True if type `sub` equals `sup` or inherits from it."""
        t: str | None = sub
        while t is not None and t != sup:
            t = self.types.get(t)
        return t is not None

    def show(self, item: Atom | Literal) -> str:
        """PDDL text of an atom or literal with the predicate spelled as in the domain."""
        if isinstance(item, Literal):
            return self.show(item.atom) if item.positive else f"(not {self.show(item.atom)})"
        return "(" + " ".join((self.spelling.get(item.predicate, item.predicate), *item.args)) + ")"

    def condition_predicates(self) -> frozenset[str]:
        """Predicates in the conditions of conditional effects (all static): the facts that
        `Action.instantiate` needs."""
        return frozenset(
            lit.atom.predicate
            for act in self.actions.values()
            for ce in act.cond_effects
            for lit in ce.condition
            if lit.atom.predicate != "="
        )

    def fluent_predicates(self) -> frozenset[str]:
        """Predicates that occur in some effect; all others are static."""
        return frozenset(
            a.predicate
            for act in self.actions.values()
            for a in (
                *act.add_effects,
                *act.del_effects,
                *(x for ce in act.cond_effects for x in (*ce.add, *ce.delete)),
            )
        )


class Problem(NamedTuple):
    """A parsed problem; `objects` maps object name to type (domain constants excluded).

    Equality ignores `source`.
    """

    name: str
    domain_name: str
    objects: Mapping[str, str]
    init: frozenset[Atom]
    goal: tuple[Literal, ...]
    source: str = "<string>"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Problem) and self[:5] == other[:5]

    def __repr__(self) -> str:  # the compared fields only
        shown = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields[:5])
        return f"Problem({shown})"

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = None  # type: ignore[assignment]  # `objects` is not hashable
