"""The package's import graph: no cycle among `utamp_gym` modules at module level, and no
import of our own modules inside a function unless it says why (``# lazy: <reason>``).

Why: an import inside a function can hide an arrow between two of the project's modules,
and with it a cycle; the rule (developers' guide) allows one only to keep a heavy
third-party dependency off a hot path, or to break a cycle too large to restructure, and
then the line (or the one above it) says so with a ``# lazy:`` comment.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "utamp_gym"
LAZY = "# lazy:"


def _name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _targets(node: ast.Import | ast.ImportFrom, module: str) -> list[str]:
    """The own modules an import statement in `module` loads explicitly."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        base = node.module or ""
        if node.level:  # relative: from the package of `module`
            pkg = module.split(".")
            is_pkg = MODULES[module].name == "__init__.py"
            pkg = pkg if is_pkg else pkg[:-1]
            pkg = pkg[: len(pkg) - node.level + 1]
            base = ".".join([*pkg, base] if base else pkg)
        names = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base for a in node.names]
    return [n for n in dict.fromkeys(names) if n in MODULES]


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _module_level(tree: ast.Module) -> list[ast.Import | ast.ImportFrom]:
    """Imports run when the module is imported (not in functions or TYPE_CHECKING blocks)."""
    out: list[ast.Import | ast.ImportFrom] = []
    todo: list[ast.stmt] = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Import | ast.ImportFrom):
            out.append(node)
        elif isinstance(node, ast.If):
            if not _is_type_checking(node):
                todo += node.body + node.orelse
        elif isinstance(node, ast.Try):
            todo += node.body + node.orelse + node.finalbody
            for h in node.handlers:
                todo += h.body
        elif isinstance(node, ast.With):
            todo += node.body
    return out


def _in_functions(tree: ast.Module) -> list[ast.Import | ast.ImportFrom]:
    out = []
    for fn in ast.walk(tree):
        if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
            for node in ast.walk(fn):
                if isinstance(node, ast.Import | ast.ImportFrom):
                    out.append(node)
    return out


def _with_packages(module: str) -> list[str]:
    """`module` and the packages whose ``__init__`` importing it runs first (below the root)."""
    parts = module.split(".")
    return [".".join(parts[:i]) for i in range(2, len(parts))] + [module]


def import_graph() -> dict[str, set[str]]:
    """Module -> the own modules its module-level imports load (with their packages)."""
    graph: dict[str, set[str]] = {}
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text(), str(path))
        loaded = {p for node in _module_level(tree) for t in _targets(node, name)
                  for p in _with_packages(t)}  # fmt: skip
        own = set(_with_packages(name))  # its own packages are running already
        graph[name] = loaded - own
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def uncommented_lazy_imports() -> list[str]:
    """``path:line`` of every in-function import of an own module without ``# lazy:``."""
    bad = []
    for name, path in MODULES.items():
        text = path.read_text()
        lines = text.splitlines()
        for node in _in_functions(ast.parse(text, str(path))):
            if not _targets(node, name):
                continue
            here = lines[node.lineno - 1]
            above = lines[node.lineno - 2] if node.lineno > 1 else ""
            if LAZY not in here and not above.strip().startswith(LAZY):
                bad.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}")
    return bad


def test_no_import_cycle_among_the_package_modules() -> None:
    found = cycles(import_graph())
    assert not found, "import cycles at module level: " + "; ".join(" <-> ".join(c) for c in found)


def test_every_in_function_import_of_an_own_module_says_why() -> None:
    bad = uncommented_lazy_imports()
    assert not bad, f"in-function imports of utamp_gym modules without '{LAZY} <reason>': {bad}"


def test_the_checks_see_a_cycle_and_an_uncommented_import() -> None:
    """The checks themselves can fail: a made-up cycle and the graph's own edges."""
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    graph = import_graph()
    assert "utamp_gym.errors" in graph["utamp_gym.agents.open_loop"]
    tree = ast.parse("def f():\n    from utamp_gym.errors import UtampError\n")
    node = _in_functions(tree)[0]
    assert _targets(node, "utamp_gym.cli") == ["utamp_gym.errors"]
