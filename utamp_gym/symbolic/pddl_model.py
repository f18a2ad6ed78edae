"""The parsed form of a PDDL task: atoms, literals, actions, domains and problems.

Plain frozen data, produced by `utamp_gym.symbolic.pddl` and read by the validator,
the grounder, the SAS writer and the envs. Names are lower-case.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Atom:
    """A predicate applied to arguments (variables ``?x``, constants or objects)."""

    predicate: str
    args: tuple[str, ...] = ()

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.args)) + ")"


@dataclass(frozen=True)
class Literal:
    """An atom or its negation; predicate ``=`` means equality of its two arguments."""

    atom: Atom
    positive: bool = True

    def __str__(self) -> str:
        return str(self.atom) if self.positive else f"(not {self.atom})"


@dataclass(frozen=True)
class Action:
    """An action schema: typed parameters, precondition literals, add and delete effects."""

    name: str
    parameters: tuple[tuple[str, str], ...]  # (?var, type)
    precondition: tuple[Literal, ...]
    add_effects: tuple[Atom, ...]
    del_effects: tuple[Atom, ...]

    @property
    def arity(self) -> int:
        return len(self.parameters)

    def instantiate(
        self, args: Iterable[str]
    ) -> tuple[tuple[Literal, ...], tuple[Atom, ...], tuple[Atom, ...]]:
        """Substitute `args` for the parameters: (precondition, add effects, delete effects)."""
        sub = dict(zip((v for v, _ in self.parameters), args, strict=True))

        def atom(a: Atom) -> Atom:
            return Atom(a.predicate, tuple(sub.get(x, x) for x in a.args))

        pre = tuple(Literal(atom(lit.atom), lit.positive) for lit in self.precondition)
        return pre, tuple(map(atom, self.add_effects)), tuple(map(atom, self.del_effects))


@dataclass(frozen=True)
class Domain:
    """A parsed domain; mappings are read-only and `types` maps each type to its parent."""

    name: str
    requirements: tuple[str, ...]
    types: Mapping[str, str | None]
    constants: Mapping[str, str]  # name -> type
    predicates: Mapping[str, tuple[str, ...]]  # name -> argument types
    actions: Mapping[str, Action]
    spelling: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)
    source: str = field(default="<string>", compare=False, repr=False)

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

    def fluent_predicates(self) -> frozenset[str]:
        """Predicates that occur in some effect; all others are static."""
        return frozenset(
            a.predicate
            for act in self.actions.values()
            for a in (*act.add_effects, *act.del_effects)
        )


@dataclass(frozen=True)
class Problem:
    """A parsed problem; `objects` maps object name to type (domain constants excluded)."""

    name: str
    domain_name: str
    objects: Mapping[str, str]
    init: frozenset[Atom]
    goal: tuple[Literal, ...]
    source: str = field(default="<string>", compare=False, repr=False)
