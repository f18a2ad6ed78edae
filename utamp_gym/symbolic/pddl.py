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

from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl_model import Action, Atom, CondEffect, Domain, Literal, Problem

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
_TOKEN = re.compile(r"\(|\)|[^\s()]+")
_STEP = re.compile(r"\(\s*([^\s()]+(?:\s+[^\s()]+)*)\s*\)")
_KEYWORDS = ("and", "not", "or", "imply", "forall", "exists", "when", "either", "increase")


class _Node:
    """A parenthesised list with the line it opens on (tokens keep their original case)."""

    __slots__ = ("items", "line")

    def __init__(self, line: int, items: list[str | _Node] | None = None) -> None:
        self.line = line
        self.items: list[str | _Node] = [] if items is None else items


def _fail(source: str, line: int | None, message: str) -> PddlError:
    return PddlError(f"{source}:{line}: {message}" if line else f"{source}: {message}")


def _read(text: str, source: str) -> list[str | _Node]:
    """Tokenise and nest; `;` starts a comment. Unbalanced parentheses report the line.

    For a '(' never closed, the line reported is the first list still open when a '(' starts
    a later line at or left of its column (in indented PDDL, the likely culprit), else the
    innermost unclosed list.
    """
    stack, cols, suspect = [_Node(0)], [-1], None
    for lineno, raw in enumerate(text.splitlines(), 1):
        for match in _TOKEN.finditer(raw.split(";", 1)[0]):
            tok = match.group()
            if tok == "(":
                if suspect is None and stack[-1].line < lineno and cols[-1] >= match.start():
                    suspect = stack[-1].line
                stack[-1].items.append(node := _Node(lineno))
                stack.append(node)
                cols.append(match.start())
            elif tok == ")":
                if len(stack) == 1:
                    raise _fail(source, lineno, "unbalanced parentheses: ')' has no matching '('")
                stack.pop()
                cols.pop()
            else:
                stack[-1].items.append(tok)
    if len(stack) > 1:
        raise _fail(
            source, suspect or stack[-1].line, "unbalanced parentheses: '(' is never closed"
        )
    return stack[0].items


class _Parser:
    """Shared helpers. `source` is named in every error; `predicates` None = syntax only."""

    def __init__(self, source: str, predicates: Mapping[str, tuple[str, ...]] | None = None):
        self.source = source
        self.predicates = predicates

    def fail(self, where: _Node | int | None, message: str) -> PddlError:
        return _fail(self.source, where.line if isinstance(where, _Node) else where, message)

    def sym(self, item: str | _Node, what: str) -> str:
        if isinstance(item, _Node):
            raise self.fail(item, f"expected {what}, got a parenthesised list")
        return item.lower()

    def node(self, item: str | _Node, line: int, what: str) -> _Node:
        if not isinstance(item, _Node):
            raise self.fail(line, f"expected {what}, got '{item}'")
        return item

    def define(self, text: str, kind: str) -> tuple[str, _Node]:
        """Check ``(define (kind NAME) ...)``; return NAME and the define node."""
        top = _read(text, self.source)
        root = top[0] if len(top) == 1 and isinstance(top[0], _Node) else None
        head = root.items[1] if root is not None and len(root.items) > 1 else None
        if not (
            root
            and str(root.items[0]).lower() == "define"
            and isinstance(head, _Node)
            and len(head.items) == 2
            and str(head.items[0]).lower() == kind
        ):
            raise self.fail(root, f"expected exactly one (define ({kind} NAME) ...)")
        return self.sym(head.items[1], f"{kind} name"), root

    def sections(self, root: _Node) -> Iterable[tuple[str, _Node]]:
        for item in root.items[2:]:
            sec = self.node(item, root.line, "a (:section ...)")
            yield (self.sym(sec.items[0], "a section keyword") if sec.items else ""), sec

    def typed_list(
        self,
        items: list[str | _Node],
        line: int,
        variables: bool,
        types: Mapping[str, object] | None = None,
    ) -> list[tuple[str, str]]:
        """Parse ``a b - t c`` into [(a, t), (b, t), (c, object)]; check types if given."""
        out: list[tuple[str, str]] = []
        pending: list[str] = []
        it = iter(items)
        for item in it:
            name = self.sym(item, "a name")
            if name == "-":
                typ = next(it, None)
                if typ is None or isinstance(typ, _Node):
                    raise self.fail(line, "'-' must be followed by a plain type name")
                out += [(p, typ.lower()) for p in pending]
                pending = []
            elif variables != name.startswith("?"):
                kind = "a variable ?x" if variables else "a name (not a variable)"
                raise self.fail(line, f"expected {kind}, got '{name}'")
            else:
                pending.append(name)
        out += [(p, "object") for p in pending]
        for name, typ in out if types is not None else ():
            if typ not in types:
                raise self.fail(
                    line, f"unknown type '{typ}' of '{name}'; declared: {', '.join(sorted(types))}"
                )
        return out

    def literals(
        self, item: str | _Node, line: int, ok: Iterable[str] | None, allow_eq: bool, what: str
    ) -> list[Literal]:
        """Parse a conjunction (``(and ...)``, ``()`` or a single literal)."""
        node = self.node(item, line, what)
        if not node.items:
            return []
        conj = node.items[1:] if str(node.items[0]).lower() == "and" else [node]
        out = []
        for x in conj:
            lit = self.node(x, node.line, f"a literal in {what}")
            neg = len(lit.items) == 2 and str(lit.items[0]).lower() == "not"
            atom = self.node(lit.items[1], lit.line, f"an atom in {what}") if neg else lit
            out.append(Literal(self.atom(atom, ok, allow_eq, what), not neg))
        return out

    def atom(self, node: _Node, ok: Iterable[str] | None, allow_eq: bool, what: str) -> Atom:
        """Parse ``(pred arg ...)`` checking predicate, arity and that every arg is in `ok`."""
        if not node.items:
            raise self.fail(node, f"empty atom in {what}")
        pred = self.sym(node.items[0], "a predicate")
        if pred in _KEYWORDS or (pred == "=" and not allow_eq):
            raise self.fail(
                node,
                f"unsupported '{pred}' in {what} (supported: a conjunction of "
                f"atoms and (not atom){' and (= a b)' if allow_eq else ''})",
            )
        args = tuple(self.sym(x, "an argument") for x in node.items[1:])
        if self.predicates is None and pred != "=":
            return Atom(pred, args)
        if pred != "=" and pred not in self.predicates:
            raise self.fail(
                node,
                f"unknown predicate '{pred}' in {what}; "
                f"declared: {', '.join(sorted(self.predicates))}",
            )
        arity = 2 if pred == "=" else len(self.predicates[pred])
        if len(args) != arity:
            raise self.fail(
                node,
                f"wrong arity for '{pred}' in {what}: expects {arity} argument(s), got {len(args)}",
            )
        bad = [a for a in args if ok is not None and a not in ok]
        if bad:
            kind = "variable" if bad[0].startswith("?") else "object"
            raise self.fail(node, f"unknown {kind} '{bad[0]}' in {what}")
        return Atom(pred, args)


@lru_cache(maxsize=16)
def cached_domain(text: str, source: str = "<string>") -> Domain:
    """`parse_domain`, remembered: a `Domain` is immutable, and planners parse the same
    domain text on every call."""
    return parse_domain(text, source)


def parse_domain(text: str, source: str = "<string>") -> Domain:
    """Parse domain text; `source` (usually the file path) is named in every error."""
    preds: dict[str, tuple[str, ...]] = {}
    p = _Parser(source, preds)
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
    p: _Parser, sec: _Node, types: Mapping[str, str | None], constants: Mapping[str, str]
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
    pnode = p.node(fields.get(":parameters", _Node(sec.line)), sec.line, "a parameter list")
    params = p.typed_list(pnode.items, pnode.line, True, types)
    if len({v for v, _ in params}) != len(params):
        raise p.fail(pnode, f"action '{name}': duplicate parameter name")
    ok = {v for v, _ in params} | set(constants)
    pre = p.literals(
        fields.get(":precondition", _Node(sec.line)),
        sec.line,
        ok,
        True,
        f"precondition of '{name}'",
    )
    eff = fields.get(":effect", _Node(sec.line))
    adds, dels, conds = _parse_effect(p, eff, sec.line, ok, f"effect of '{name}'", types)
    return Action(name, tuple(params), tuple(pre), tuple(adds), tuple(dels), tuple(conds))


def _head(item: str | _Node) -> str:
    return str(item.items[0]).lower() if isinstance(item, _Node) and item.items else ""


def _parse_effect(
    p: _Parser,
    item: str | _Node,
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
    p: _Parser, node: _Node, ok: set[str], what: str, types: Mapping[str, str | None]
) -> CondEffect:
    """``(forall (?v - t ...) (when COND EFF))`` or ``(when COND EFF)``; see the module doc."""
    variables: list[tuple[str, str]] = []
    body: str | _Node = node
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
    assert isinstance(body, _Node)
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
    p: _Parser, actions: Iterable[Action], lines: Mapping[str, int]
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
    p = _Parser(source)
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
    p = _Parser(problem.source, domain.predicates)
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
        p.atom(_Node(lines.get(a, 0), [a.predicate, *a.args]), ok, False, "the initial state")
    for lit in problem.goal:
        p.atom(
            _Node(lines.get(lit, 0), [lit.atom.predicate, *lit.atom.args]), ok, False, "the goal"
        )


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
            raise _fail(source, lineno, f"expected one '(action arg ...)' per line, got '{body}'")
        steps.append(tuple(match.group(1).lower().split()))
    return steps
