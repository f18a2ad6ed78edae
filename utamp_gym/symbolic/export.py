"""PDDL files for other planners: object names that are also domain symbols get new names.

PDDL keeps predicates, types, actions and objects in separate name spaces, and Fast Downward
and our parser accept a problem whose object shares a name with, say, a predicate (the
procedural scenes' object ``base`` and the domain's predicate ``base``). Other tools keep one
name space: unified-planning's reader refuses such a problem ("Name base already defined!").
`export_task` writes the problem with every such object renamed (``base`` -> ``base-obj``,
a name that collides with nothing else), the plan with the same names, and one comment line
per renaming at the top of the problem, which `renames_in` reads back; `scene_plan` maps a
plan over the exported names (from any planner) back to the scene's names.

The planner itself never sees the exported text (it plans the scene's atoms), so renaming
changes no plan of ours.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Mapping
from types import MappingProxyType
from typing import NamedTuple

from utamp_gym.symbolic.pddl import Domain, cached_domain, parse_problem

__all__ = [
    "PDDL_KEYWORDS",
    "ExportedTask",
    "colliding_objects",
    "domain_symbols",
    "export_task",
    "exported_plan",
    "renames_in",
    "scene_plan",
]

# fmt: off
#: the reserved words of PDDL 3.1 (section names start with ':' and cannot clash)
PDDL_KEYWORDS = frozenset({
    "define", "domain", "problem", "and", "or", "not", "imply", "exists", "forall", "when",
    "either", "object", "number", "at", "over", "all", "start", "end", "increase", "decrease",
    "assign", "scale-up", "scale-down", "minimize", "maximize", "total-time", "preference",
    "always", "sometime", "within", "at-most-once", "sometime-after", "sometime-before",
    "always-within", "hold-during", "hold-after", "is-violated"
})
# fmt: on
_TOKEN = re.compile(r"\(|\)|[^\s()]+")
_SECTIONS = (":objects", ":init", ":goal")  # where object names occur in a problem
_RENAME_LINE = re.compile(r"^; renamed object: (\S+) -> (\S+)", re.M)


class ExportedTask(NamedTuple):
    """Domain, problem and plan texts as written for other planners, and the renamings
    (scene name -> exported name; empty if no name collided)."""

    domain: str
    problem: str
    plan: tuple[str, ...]
    renames: Mapping[str, str]


def domain_symbols(domain: Domain) -> frozenset[str]:
    """Every name an object must not take: the domain's name, types, constants, predicates
    and actions, and the PDDL keywords (lower-case)."""
    return (
        frozenset(
            (domain.name, *domain.types, *domain.constants, *domain.predicates, *domain.actions)
        )
        | PDDL_KEYWORDS
    )


def _kind(domain: Domain, name: str) -> str:
    """What `name` is in `domain` (for the comment that explains a renaming)."""
    for kind, names in (
        ("predicate", domain.predicates),
        ("action", domain.actions),
        ("type", domain.types),
        ("constant", domain.constants),
    ):
        if name in names:
            return f"a {kind} of domain {domain.name}"
    return f"the name of domain {domain.name}" if name == domain.name else "a PDDL keyword"


def colliding_objects(domain: Domain, objects: Iterable[str]) -> dict[str, str]:
    """New names for the `objects` that are domain symbols, in order: ``NAME-obj``, or
    ``NAME-obj2``, ``NAME-obj3``, ... if that is taken (by a symbol or another object)."""
    symbols = domain_symbols(domain)
    objects = [o.lower() for o in objects]
    taken = set(symbols) | set(objects)
    renames: dict[str, str] = {}
    for name in objects:
        if name in symbols and name not in renames:
            new = next(
                c
                for k in itertools.count(1)
                if (c := f"{name}-obj{k if k > 1 else ''}") not in taken
            )
            taken.add(new)
            renames[name] = new
    return renames


def _rename_problem(text: str, renames: Mapping[str, str]) -> str:
    """`text` with each object of `renames` renamed where it stands as an object: in the
    :objects, :init and :goal sections, neither as a list's head (a predicate or ``and``) nor
    as the type after ``-``. Layout and comments are kept."""
    out: list[str] = []
    depth, section, head, typed = 0, "", False, False
    for line in text.splitlines(keepends=True):
        code, sep, comment = line.partition(";")
        pieces, pos = [], 0
        for m in _TOKEN.finditer(code):
            tok = m.group()
            if tok == "(":
                depth, head = depth + 1, True
                continue
            if tok == ")":
                depth, head = depth - 1, False
                if depth < 2:
                    section = ""
                continue
            new = None
            if head:
                if depth == 2:
                    section = tok.lower()
            elif typed:
                pass
            elif section in _SECTIONS:
                new = renames.get(tok.lower())
            head, typed = False, tok == "-"
            if new is not None:
                pieces += [code[pos : m.start()], new]
                pos = m.end()
        out.append("".join(pieces) + code[pos:] + sep + comment)
    return "".join(out)


def _rename_step(step: str, renames: Mapping[str, str]) -> str:
    """``(action a b)`` with its arguments renamed (the action name kept)."""
    words = step.strip().strip("()").split()
    if not words or not renames:
        return step
    args = (renames.get(w.lower(), w) for w in words[1:])
    return "(" + " ".join((words[0], *args)) + ")"


def exported_plan(plan: Iterable[str], renames: Mapping[str, str]) -> tuple[str, ...]:
    """A plan over the scene's names as steps over the exported names."""
    return tuple(_rename_step(s, renames) for s in plan)


def scene_plan(plan: Iterable[str], renames: Mapping[str, str]) -> tuple[str, ...]:
    """A plan over the exported names (e.g. from another planner) over the scene's names."""
    back = {new: old for old, new in renames.items()}
    return tuple(_rename_step(s, back) for s in plan)


def renames_in(problem_text: str) -> dict[str, str]:
    """The renamings an exported problem records (scene name -> exported name)."""
    return dict(_RENAME_LINE.findall(problem_text))


def export_task(
    domain_text: str, problem_text: str, plan: Iterable[str] = (), source: str = "problem"
) -> ExportedTask:
    """The task as written for other planners (see the module docstring); `plan` is over
    the scene's names. The domain text is unchanged."""
    domain = cached_domain(domain_text, "domain")
    objects = parse_problem(problem_text, source=source).objects
    renames = colliding_objects(domain, objects)
    problem = problem_text
    if renames:
        notes = "".join(
            f"; renamed object: {old} -> {new} ('{old}' is {_kind(domain, old)})\n"
            for old, new in renames.items()
        )
        problem = notes + _rename_problem(problem_text, renames)
    return ExportedTask(
        domain_text, problem, exported_plan(plan, renames), MappingProxyType(renames)
    )
