"""What the planner keeps on disk between processes: parsed domains and their join orders.

Why: a fresh process (``utamp plan``, an evaluation worker) parses its domain and orders the
grounder's joins (`symbolic.join_store`) before it grounds anything, about a quarter of a
five-object plan's time in the process. Both are pure functions of the domain's text and of
the code that computes them, so each is kept with a key naming both in full (the input's
text, and the size and modification time of the modules' sources, as Python's byte-code
cache does), under a file name made from a CRC of the key
(``$XDG_CACHE_HOME/utamp_gym/<kind>-<crc>.bin``, ``~/.cache`` without XDG_CACHE_HOME); a
file is used only when its key equals the one asked for. It holds plain tuples of strings,
ints, booleans and None in `marshal`'s format, which builds them without parsing text (JSON
took as long to read as the work takes to redo) and executes nothing. It is written whole
and atomically; one that cannot be read, does not match or cannot be written is ignored and
the work is done as before. ``UTAMP_PLAN_CACHE=0`` turns the store off. (No hashlib or
tempfile here: ``utamp plan`` would import them for this alone.)
"""

from __future__ import annotations

import marshal
import os
import sys
import zlib
from functools import lru_cache
from pathlib import Path
from types import MappingProxyType
from typing import Any

from utamp_gym.symbolic.pddl_model import Action, Atom, CondEffect, Domain, Literal

#: bump when the stored layout changes
LAYOUT = 1
#: what a stored file may fail with (anything else is a bug)
UNREADABLE = (OSError, EOFError, ValueError, KeyError, TypeError, IndexError, AttributeError)


@lru_cache(maxsize=8)
def sources(*modules: str) -> str:
    """The source files of `modules` (imported module names) with their sizes and
    modification times (OSError if one cannot be found)."""
    out = []
    for name in modules:
        path = sys.modules[name].__file__ or ""
        st = os.stat(path)
        out.append(f"{path}:{st.st_size}:{st.st_mtime_ns}")
    return "|".join(out)


def key_of(*parts: str) -> str:
    """The key of `parts` (with the layout)."""
    return "\x00".join((str(LAYOUT), *parts))


def path_of(kind: str, key: str) -> Path | None:
    """Where `kind`'s data under `key` is kept (None: the store is off)."""
    if os.environ.get("UTAMP_PLAN_CACHE", "1") == "0":
        return None
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    crc = zlib.crc32(key.encode())
    return Path(root) / "utamp_gym" / f"{kind}-{crc:08x}-{len(key)}.bin"


def load(kind: str, key: str) -> Any:
    """The data stored for `key`, or None."""
    path = path_of(kind, key)
    if path is None:
        return None
    try:
        stored_key, data = marshal.loads(path.read_bytes())
    except UNREADABLE:
        return None
    return data if stored_key == key else None


def save(kind: str, key: str, data: Any) -> None:
    """Store `data` (plain tuples) for `key`: a temporary file renamed; a failure leaves
    nothing behind."""
    path = path_of(kind, key)
    if path is None:
        return
    import tempfile  # only a first run writes

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{kind}-", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(marshal.dumps((key, data)))
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    except (OSError, ValueError):
        pass


# ---------------------------------------------------------------------------- domains
def _atoms(atoms: tuple[Atom, ...]) -> tuple[tuple[str, tuple[str, ...]], ...]:
    return tuple((a.predicate, a.args) for a in atoms)


def _lits(lits: tuple[Literal, ...]) -> tuple[tuple[str, tuple[str, ...], bool], ...]:
    return tuple((lit.atom.predicate, lit.atom.args, lit.positive) for lit in lits)


def encode_domain(d: Domain) -> tuple[Any, ...]:
    """`d` as plain tuples (`decode_domain` undoes it)."""
    actions = tuple(
        (a.name, a.parameters, _lits(a.precondition), _atoms(a.add_effects),
         _atoms(a.del_effects),
         tuple((c.variables, _lits(c.condition), _atoms(c.add), _atoms(c.delete))
               for c in a.cond_effects))
        for a in d.actions.values()
    )  # fmt: skip
    return (d.name, d.requirements, tuple(d.types.items()), tuple(d.constants.items()),
            tuple(d.predicates.items()), actions, tuple(d.spelling.items()), d.source)  # fmt: skip


_new = tuple.__new__  # a named tuple without its Python-level __new__


def _a(atoms: tuple[tuple[str, tuple[str, ...]], ...]) -> tuple[Atom, ...]:
    return tuple(_new(Atom, a) for a in atoms)


def _l(lits: tuple[tuple[str, tuple[str, ...], bool], ...]) -> tuple[Literal, ...]:
    return tuple(_new(Literal, (_new(Atom, (p, args)), pos)) for p, args, pos in lits)


def decode_domain(data: tuple[Any, ...]) -> Domain:
    """The `Domain` of `encode_domain`'s tuples (TypeError if they are not such tuples)."""
    name, reqs, types, constants, predicates, actions, spelling, source = data
    acts = {}
    for aname, params, pre, add, dele, conds in actions:
        ces = tuple(_new(CondEffect, (v, _l(c), _a(ad), _a(de))) for v, c, ad, de in conds)
        acts[aname] = _new(Action, (aname, params, _l(pre), _a(add), _a(dele), ces))
    if not all(isinstance(x, str) for x in (name, source, *reqs)):
        raise TypeError("not a stored domain")
    return Domain(name, reqs, MappingProxyType(dict(types)), MappingProxyType(dict(constants)),
                  MappingProxyType(dict(predicates)), MappingProxyType(acts),
                  MappingProxyType(dict(spelling)), source)  # fmt: skip


__all__ = [
    "LAYOUT",
    "decode_domain",
    "encode_domain",
    "key_of",
    "load",
    "path_of",
    "save",
    "sources",
]
