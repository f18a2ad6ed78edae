"""Parser for the PDDL subset of the U-TAMP domains (``:strips :typing
:negative-preconditions :equality :conditional-effects``): typed types/constants/predicates,
actions with conjunctive preconditions (literals, ``=``, ``not =``) and effects (atoms,
``not atom``, and ``(forall (?v - t ...) (when COND EFFECTS))`` or ``(when COND EFFECTS)``
whose condition is a conjunction of literals over *static* predicates in which every ``?v``
occurs positively), problems with objects, init and a conjunctive goal. Anything else raises
`PddlError` naming the source, line and problem, so an unsupported file fails at load time,
not silently.

Names are case-insensitive (lower-cased); `Domain.spelling` keeps predicate names as
declared so that messages can show ``(canLift tray tray-handle-left)``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from functools import lru_cache
from types import MappingProxyType

from utamp_gym.symbolic import store
from utamp_gym.symbolic.pddl_model import Action, Atom, CondEffect, Domain, Literal, Problem
from utamp_gym.symbolic.pddl_reader import Node, Parser, fail

__all__ = [
    "Action",
    "Atom",
    "CondEffect",
    "Domain",
    "Literal",
    "Problem",
    "cached_domain",
    "check_problem",
    "parse_domain",
    "parse_plan",
    "parse_problem",
]

SUPPORTED_REQUIREMENTS = (
    ":strips",
    ":typing",
    ":negative-preconditions",
    ":equality",
    ":conditional-effects",
)
_STEP = re.compile(r"\(\s*([^\s()]+(?:\s+[^\s()]+)*)\s*\)")


@lru_cache(maxsize=16)
def cached_domain(text: str, source: str = "<string>") -> Domain:
    """`parse_domain`, remembered: a `Domain` is immutable, and planners parse the same
    domain text on every call; kept on disk too (`symbolic.store`), for the next process."""
    try:
        code = store.sources(__name__, Domain.__module__, Parser.__module__)
        key = store.key_of(code, source, text)
    except OSError:  # the parser's source cannot be read: no store
        return parse_domain(text, source)
    data = store.load("domain", key)
    if data is not None:
        try:
            return store.decode_domain(data)
        except store.UNREADABLE:
            pass
    domain = parse_domain(text, source)
    store.save("domain", key, store.encode_domain(domain))
    return domain


def parse_domain(text: str, source: str = "<string>") -> Domain:
    """Parse domain text; `source` (usually the file path) is named in every error."""
    preds: dict[str, tuple[str, ...]] = {}
    p = Parser(source, preds)
    name, root = p.define(text, "domain")
    reqs: list[str] = []
    types: dict[str, str | None] = {"object": None}
    constants: dict[str, str] = {}
    actions: dict[str, Action] = {}
    spelling: dict[str, str] = {}
    lines: dict[str, int] = {}
    for key, sec in p.sections(root):
        body = sec.items[1:]
        if key == ":requirements":
            reqs = [p.sym(r, "a requirement") for r in body]
            bad = [r for r in reqs if r not in SUPPORTED_REQUIREMENTS]
            if bad:
                raise p.fail(
                    sec,
                    f"unsupported requirement(s) {' '.join(bad)}; "
                    f"supported: {' '.join(SUPPORTED_REQUIREMENTS)}",
                )
        elif key == ":types":
            for t, parent in p.typed_list(body, sec.line, variables=False):
                types[t] = parent
                types.setdefault(parent, "object" if parent != "object" else None)
            for t in types:  # reject cycles such as a - b, b - a
                seen, cur = set(), t
                while (cur := types[cur]) is not None:
                    if cur in seen or cur == t:
                        raise p.fail(sec, f"cyclic type hierarchy involving '{t}'")
                    seen.add(cur)
        elif key == ":constants":
            constants.update(p.typed_list(body, sec.line, False, types))
        elif key == ":predicates":
            for decl in body:
                d = p.node(decl, sec.line, "a predicate declaration (name ?x - type ...)")
                pname = p.sym(d.items[0], "a predicate name") if d.items else ""
                if not pname or pname in preds:
                    raise p.fail(d, f"empty or duplicate predicate declaration '{pname}'")
                preds[pname] = tuple(t for _, t in p.typed_list(d.items[1:], d.line, True, types))
                spelling[pname] = str(d.items[0])
        elif key == ":action":
            act = _parse_action(p, sec, types, constants)
            if act.name in actions:
                raise p.fail(sec, f"duplicate action '{act.name}'")
            actions[act.name] = act
            lines[act.name] = sec.line
        else:
            raise p.fail(
                sec,
                f"unsupported domain section '{key}'; supported: :requirements "
                ":types :constants :predicates :action",
            )
    _check_static_conditions(p, actions.values(), lines)
    return Domain(
        name,
        tuple(reqs),
        MappingProxyType(types),
        MappingProxyType(constants),
        MappingProxyType(preds),
        MappingProxyType(actions),
        MappingProxyType(spelling),
        source,
    )


def _parse_action(
    p: Parser, sec: Node, types: Mapping[str, str | None], constants: Mapping[str, str]
) -> Action:
    name = p.sym(sec.items[1], "an action name") if len(sec.items) > 1 else ""
    rest = sec.items[2:]
    keys = [p.sym(k, "a keyword") for k in rest[::2]]
    fields = dict(zip(keys, rest[1::2], strict=False))
    if not name or len(rest) % 2 or set(keys) - {":parameters", ":precondition", ":effect"}:
        raise p.fail(
            sec,
            f"action '{name}': expected (:action NAME :parameters (...) "
            ":precondition (...) :effect (...))",
        )
    pnode = p.node(fields.get(":parameters", Node(sec.line)), sec.line, "a parameter list")
    params = p.typed_list(pnode.items, pnode.line, True, types)
    if len({v for v, _ in params}) != len(params):
        raise p.fail(pnode, f"action '{name}': duplicate parameter name")
    ok = {v for v, _ in params} | set(constants)
    pre = p.literals(
        fields.get(":precondition", Node(sec.line)),
        sec.line,
        ok,
        True,
        f"precondition of '{name}'",
    )
    eff = fields.get(":effect", Node(sec.line))
    adds, dels, conds = _parse_effect(p, eff, sec.line, ok, f"effect of '{name}'", types)
    return Action(name, tuple(params), tuple(pre), tuple(adds), tuple(dels), tuple(conds))


def _head(item: str | Node) -> str:
    return str(item.items[0]).lower() if isinstance(item, Node) and item.items else ""


def _parse_effect(
    p: Parser,
    item: str | Node,
    line: int,
    ok: set[str],
    what: str,
    types: Mapping[str, str | None],
) -> tuple[list[Atom], list[Atom], list[CondEffect]]:
    """Parse an effect: a conjunction of atoms, ``(not atom)`` and conditional effects."""
    node = p.node(item, line, what)
    conj = node.items[1:] if _head(node) == "and" else [node] if node.items else []
    adds: list[Atom] = []
    dels: list[Atom] = []
    conds: list[CondEffect] = []
    for x in conj:
        head = _head(x)
        if head in ("forall", "when"):
            conds.append(_parse_cond_effect(p, p.node(x, node.line, what), ok, what, types))
            continue
        for lit in p.literals(x, node.line, ok, False, what):
            (adds if lit.positive else dels).append(lit.atom)
    return adds, dels, conds


def _parse_cond_effect(
    p: Parser, node: Node, ok: set[str], what: str, types: Mapping[str, str | None]
) -> CondEffect:
    """``(forall (?v - t ...) (when COND EFF))`` or ``(when COND EFF)``; see the module doc."""
    variables: list[tuple[str, str]] = []
    body: str | Node = node
    if _head(node) == "forall":
        if len(node.items) != 3:
            raise p.fail(node, f"expected (forall (?v - type ...) (when ...)) in {what}")
        vnode = p.node(node.items[1], node.line, "a variable list")
        variables = p.typed_list(vnode.items, vnode.line, True, types)
        names = [v for v, _ in variables]
        twice = next((v for i, v in enumerate(names) if v in ok or v in names[:i]), None)
        if twice is not None:
            raise p.fail(node, f"forall variable '{twice}' in {what} is declared twice")
        body = node.items[2]
    if _head(body) != "when" or len(p.node(body, node.line, what).items) != 3:
        raise p.fail(
            node,
            f"unsupported conditional effect in {what}: expected (forall (?v - type ...) "
            "(when CONDITION EFFECTS)) or (when CONDITION EFFECTS)",
        )
    assert isinstance(body, Node)
    inner = ok | {v for v, _ in variables}
    cond = p.literals(body.items[1], body.line, inner, True, f"the condition of a when in {what}")
    effect = p.literals(body.items[2], body.line, inner, False, f"a when in {what}")
    arg_types = p.predicates or {}
    for var, typ in variables:
        if not any(
            lit.positive
            and lit.atom.predicate != "="
            and any(
                a == var and _is_subtype(types, t, typ)
                for a, t in zip(lit.atom.args, arg_types[lit.atom.predicate], strict=True)
            )
            for lit in cond
        ):
            raise p.fail(
                body,
                f"forall variable '{var}' in {what} must occur in a positive condition literal "
                f"at an argument of type '{typ}' (other quantification is not supported)",
            )
    return CondEffect(
        tuple(variables),
        tuple(cond),
        tuple(lit.atom for lit in effect if lit.positive),
        tuple(lit.atom for lit in effect if not lit.positive),
    )


def _is_subtype(types: Mapping[str, str | None], sub: str, sup: str) -> bool:
    t: str | None = sub
    while t is not None and t != sup:
        t = types.get(t)
    return t is not None


def _check_static_conditions(
    p: Parser, actions: Iterable[Action], lines: Mapping[str, int]
) -> None:
    """Conditions of conditional effects may use static predicates only (resolved when
    grounding); a fluent one raises `PddlError`."""
    actions = list(actions)
    fluent = {
        a.predicate
        for act in actions
        for a in (
            *act.add_effects,
            *act.del_effects,
            *(x for ce in act.cond_effects for x in (*ce.add, *ce.delete)),
        )
    }
    for act in actions:
        for ce in act.cond_effects:
            bad = [lit for lit in ce.condition if lit.atom.predicate in fluent]
            if bad:
                raise p.fail(
                    lines.get(act.name),
                    f"effect of '{act.name}': condition {bad[0]} uses the fluent predicate "
                    f"'{bad[0].atom.predicate}'; conditions over fluent predicates are not "
                    "supported (only static ones)",
                )


def parse_problem(text: str, source: str = "<string>", domain: Domain | None = None) -> Problem:
    """Parse problem text; with `domain`, also `check_problem` (errors give the line)."""
    p = Parser(source)
    name, root = p.define(text, "problem")
    dom_name, objects, init, goal = "", {}, [], None
    lines: dict[object, int] = {}
    for key, sec in p.sections(root):
        if key == ":domain" and len(sec.items) == 2:
            dom_name = p.sym(sec.items[1], "a domain name")
        elif key == ":objects":
            objects = dict(p.typed_list(sec.items[1:], sec.line, variables=False))
            lines.update(dict.fromkeys(objects, sec.line))
        elif key == ":init":
            for item in sec.items[1:]:
                node = p.node(item, sec.line, "a ground atom")
                init.append(atom := p.atom(node, None, False, "the initial state"))
                lines[atom] = node.line
        elif key == ":goal" and len(sec.items) == 2:
            goal = p.literals(sec.items[1], sec.line, None, False, "the goal")
            lines.update(dict.fromkeys(goal, sec.line))
        elif key != ":requirements":
            raise p.fail(
                sec, f"unsupported problem section '{key}'; supported: :domain :objects :init :goal"
            )
    if goal is None:
        raise p.fail(root, "problem has no (:goal ...)")
    problem = Problem(
        name, dom_name, MappingProxyType(objects), frozenset(init), tuple(goal), source
    )
    if domain is not None:
        check_problem(domain, problem, lines)
    return problem


def check_problem(
    domain: Domain, problem: Problem, lines: Mapping[object, int] | None = None
) -> None:
    """Raise `PddlError` if `problem` does not fit `domain` (names, arities, objects, types).

    `lines` optionally maps objects, init atoms and goal literals to their source line.
    """
    lines = lines or {}
    p = Parser(problem.source, domain.predicates)
    if problem.domain_name and problem.domain_name != domain.name:
        raise p.fail(None, f"problem is for domain '{problem.domain_name}', not '{domain.name}'")
    for o, t in problem.objects.items():
        p.typed_list([o, "-", t], lines.get(o, 0), False, domain.types)
        if domain.constants.get(o, t) != t:
            raise p.fail(
                lines.get(o),
                f"object '{o}' redeclares a constant of type '{domain.constants[o]}' as '{t}'",
            )
    ok = set(domain.constants) | set(problem.objects)
    for a in sorted(problem.init, key=lambda a: (lines.get(a, 0), str(a))):
        p.atom(Node(lines.get(a, 0), [a.predicate, *a.args]), ok, False, "the initial state")
    for lit in problem.goal:
        p.atom(Node(lines.get(lit, 0), [lit.atom.predicate, *lit.atom.args]), ok, False, "the goal")


def parse_plan(text: str, source: str = "<string>") -> list[tuple[str, ...]]:
    """Parse a plan: one ``(action arg ...)`` per line, ``;`` comment lines, blank lines.

    Reads Fast Downward's ``sas_plan`` (whose last line is ``; cost = N (unit cost)``).
    Returns lower-case tuples ``(name, arg, ...)``.
    """
    steps: list[tuple[str, ...]] = []
    for lineno, raw in enumerate(text.splitlines(), 1):
        body = raw.split(";", 1)[0].strip()
        if not body:
            continue
        match = _STEP.fullmatch(body)
        if match is None:
            raise fail(source, lineno, f"expected one '(action arg ...)' per line, got '{body}'")
        steps.append(tuple(match.group(1).lower().split()))
    return steps
