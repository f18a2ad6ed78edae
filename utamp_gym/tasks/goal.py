"""`Goal`: what a scene asks for, as data.

A goal is a conjunction of ground literals over the U-TAMP domains' own predicates (no new
predicate is needed), each a PDDL string in lower case:

* an on-relation between object parts, ``(oc under mug board)`` (the mug stands with its
  `under` part on the board) or ``(oc on slot4 bowl)`` (the bowl stands on the table in
  slot4's region);
* a surface left clear, ``(oc on tray air)``;
* a negated relation, ``(not (oc under mug pan))``: the mug does not stand on the pan.
  Conjunctions of negated relations express what a single positive atom cannot without
  derived predicates: "X stands on one of a set of supports" (every other support
  negated; with the hand empty X stands somewhere), hence "these objects form one stack
  on the base, in any order" and "X stands on the table" (`utamp_gym.tasks.templates`).

The planner receives the literals as the PDDL goal (`symbolic.problem.build_problem`);
physics success is `goal_holds` on the atoms perceived in the measured state
(`perception.abstraction.perceive`). A goal also carries the template it was made from
and the template's parameters, so that the language (`utamp_gym.tasks.language`) and a
policy's goal encoding read the same data. Goals are hashable and round-trip through
plain data (`to_dict` / `from_dict`: JSON or a TOML table).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping
from typing import Any

#: the goal of no template: literals given directly (a scene file's ``[goal] atoms``)
CUSTOM = "custom"
HAND_EMPTY = "(oc in hand air)"
_ATOM = re.compile(r"\((?:[a-z][a-z0-9_-]*)(?: [a-z0-9][a-z0-9_./-]*)+\)")
_NOT = re.compile(r"\(not (\(.*\))\)")

ParamValue = str | tuple[str, ...]


def atom(*args: str) -> str:
    """A PDDL atom in lower case: ``atom("oc", "on", "tray", "air")`` -> ``(oc on tray air)``."""
    return "(" + " ".join(a.lower() for a in args) + ")"


def negated(a: str) -> str:
    return f"(not {a})"


def split_literal(literal: str) -> tuple[bool, str]:
    """(positive, atom) of a literal; ValueError naming it if it is malformed."""
    m = _NOT.fullmatch(literal)
    body = m.group(1) if m else literal
    if not _ATOM.fullmatch(body):
        raise ValueError(
            f"malformed goal literal {literal!r} (want '(pred arg ...)' or '(not (...))')"
        )
    return m is None, body


def _param(value: Any, name: str) -> ParamValue:
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        return tuple(value)
    raise ValueError(f"goal parameter {name!r}: want a name or a list of names, got {value!r}")


class Goal:
    """A set of ground literals (`literals`), the template that made them and its parameters.

    `params` are (name, value) pairs sorted by name; a value is an object, slot or attribute
    name, or a tuple of them. Two goals are equal when template, parameters and literals are.
    Immutable and hashable (a plain class: `utamp plan` imports it, and `dataclasses` costs
    its start-up a few milliseconds).
    """

    __slots__ = ("literals", "params", "template")
    template: str
    params: tuple[tuple[str, ParamValue], ...]
    literals: tuple[str, ...]

    def __init__(
        self, template: str, params: tuple[tuple[str, ParamValue], ...], literals: tuple[str, ...]
    ) -> None:
        object.__setattr__(self, "template", template)
        object.__setattr__(self, "params", tuple(params))
        object.__setattr__(self, "literals", tuple(literals))
        self._check()

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"Goal is immutable (cannot set {name!r})")

    def _key(self) -> tuple[Any, ...]:
        return (self.template, self.params, self.literals)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Goal) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        t, p, lits = self._key()
        return f"Goal(template={t!r}, params={p!r}, literals={lits!r})"

    def __reduce__(self) -> tuple[Any, ...]:
        return (Goal, self._key())

    def _check(self) -> None:
        for lit in self.literals:
            split_literal(lit)
        if len(set(self.literals)) != len(self.literals):
            raise ValueError("a goal lists a literal twice")
        names = [k for k, _ in self.params]
        if names != sorted(set(names)):
            raise ValueError("goal parameters must be sorted by name, each once")

    @classmethod
    def make(cls, template: str, params: Mapping[str, Any], literals: Iterable[str]) -> Goal:
        """A goal from a parameter mapping (sorted here) and literals (kept in order, each once)."""
        ps = tuple(sorted((k, _param(v, k)) for k, v in params.items()))
        return cls(template, ps, tuple(dict.fromkeys(lit.lower() for lit in literals)))

    @property
    def param_dict(self) -> dict[str, ParamValue]:
        return dict(self.params)

    def param(self, name: str) -> ParamValue:
        return self.param_dict[name]

    @property
    def atoms(self) -> tuple[str, ...]:
        """The literals as strings (what ``info["goal"]`` shows)."""
        return self.literals

    @property
    def positive(self) -> frozenset[str]:
        return frozenset(a for p, a in map(split_literal, self.literals) if p)

    @property
    def negative(self) -> frozenset[str]:
        return frozenset(a for p, a in map(split_literal, self.literals) if not p)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON / a TOML table): template, params (lists for tuples), atoms."""
        return {
            "template": self.template,
            "params": {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.params},
            "atoms": list(self.literals),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Goal:
        """The inverse of `to_dict` (no check against a scene: see `scene.io`)."""
        return cls.make(str(data["template"]), data.get("params", {}), data["atoms"])

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> Goal:
        return cls.from_dict(json.loads(text))


def unmet(goal: Goal, atoms: Iterable[str]) -> tuple[str, ...]:
    """The goal's literals that do not hold in a state given by its (true) atoms."""
    state = {a.lower() for a in atoms}
    out = []
    for lit in goal.literals:
        positive, a = split_literal(lit)
        if (a in state) != positive:
            out.append(lit)
    return tuple(out)


def goal_holds(goal: Goal, atoms: Iterable[str]) -> bool:
    """Whether every literal of the goal holds in the state `atoms` (e.g. `Perception.atoms`)."""
    return not unmet(goal, atoms)


__all__ = [
    "CUSTOM",
    "HAND_EMPTY",
    "Goal",
    "atom",
    "goal_holds",
    "negated",
    "split_literal",
    "unmet",
]
