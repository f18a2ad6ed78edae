"""Reading PDDL text: tokens nested into lists that remember their lines, and the checks
shared by the domain and problem parsers (`symbolic.pddl`): names, typed lists, literals
and atoms, each failing with a `PddlError` naming the source and line.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping

from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl_model import Atom, Literal

_TOKEN = re.compile(r"\(|\)|[^\s()]+")
_KEYWORDS = ("and", "not", "or", "imply", "forall", "exists", "when", "either", "increase")


class Node:
    """A parenthesised list with the line it opens on (tokens keep their original case)."""

    __slots__ = ("items", "line")

    def __init__(self, line: int, items: list[str | Node] | None = None) -> None:
        self.line = line
        self.items: list[str | Node] = [] if items is None else items


def fail(source: str, line: int | None, message: str) -> PddlError:
    return PddlError(f"{source}:{line}: {message}" if line else f"{source}: {message}")


def read(text: str, source: str) -> list[str | Node]:
    """Tokenise and nest; `;` starts a comment. Unbalanced parentheses report the line.

    For a '(' never closed, the line reported is the first list still open when a '(' starts
    a later line at or left of its column (in indented PDDL, the likely culprit), else the
    innermost unclosed list.
    """
    stack, cols, suspect = [Node(0)], [-1], None
    for lineno, raw in enumerate(text.splitlines(), 1):
        for match in _TOKEN.finditer(raw.split(";", 1)[0]):
            tok = match.group()
            if tok == "(":
                if suspect is None and stack[-1].line < lineno and cols[-1] >= match.start():
                    suspect = stack[-1].line
                stack[-1].items.append(node := Node(lineno))
                stack.append(node)
                cols.append(match.start())
            elif tok == ")":
                if len(stack) == 1:
                    raise fail(source, lineno, "unbalanced parentheses: ')' has no matching '('")
                stack.pop()
                cols.pop()
            else:
                stack[-1].items.append(tok)
    if len(stack) > 1:
        raise fail(source, suspect or stack[-1].line, "unbalanced parentheses: '(' is never closed")
    return stack[0].items


class Parser:
    """Shared helpers. `source` is named in every error; `predicates` None = syntax only."""

    def __init__(self, source: str, predicates: Mapping[str, tuple[str, ...]] | None = None):
        self.source = source
        self.predicates = predicates

    def fail(self, where: Node | int | None, message: str) -> PddlError:
        return fail(self.source, where.line if isinstance(where, Node) else where, message)

    def sym(self, item: str | Node, what: str) -> str:
        if isinstance(item, Node):
            raise self.fail(item, f"expected {what}, got a parenthesised list")
        return item.lower()

    def node(self, item: str | Node, line: int, what: str) -> Node:
        if not isinstance(item, Node):
            raise self.fail(line, f"expected {what}, got '{item}'")
        return item

    def define(self, text: str, kind: str) -> tuple[str, Node]:
        """Check ``(define (kind NAME) ...)``; return NAME and the define node."""
        top = read(text, self.source)
        root = top[0] if len(top) == 1 and isinstance(top[0], Node) else None
        head = root.items[1] if root is not None and len(root.items) > 1 else None
        if not (
            root
            and str(root.items[0]).lower() == "define"
            and isinstance(head, Node)
            and len(head.items) == 2
            and str(head.items[0]).lower() == kind
        ):
            raise self.fail(root, f"expected exactly one (define ({kind} NAME) ...)")
        return self.sym(head.items[1], f"{kind} name"), root

    def sections(self, root: Node) -> Iterable[tuple[str, Node]]:
        for item in root.items[2:]:
            sec = self.node(item, root.line, "a (:section ...)")
            yield (self.sym(sec.items[0], "a section keyword") if sec.items else ""), sec

    def typed_list(
        self,
        items: list[str | Node],
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
                if typ is None or isinstance(typ, Node):
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
        self, item: str | Node, line: int, ok: Iterable[str] | None, allow_eq: bool, what: str
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

    def atom(self, node: Node, ok: Iterable[str] | None, allow_eq: bool, what: str) -> Atom:
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


__all__ = ["Node", "Parser", "fail", "read"]
