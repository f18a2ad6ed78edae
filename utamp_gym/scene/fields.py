"""Typed, range-checked reading of scene and catalogue file values.

Every check raises `SceneError` naming the file and the field path in one uniform form:
tables by dotted keys, array entries by index, e.g. ``types.plate.parts.on.height`` or
``objects[2].position[0]``. Keys that are not bare TOML keys are quoted as TOML would
(``types."Plate!"``), so a message always stays on one line.

TOML is read with `tomli`, the library the standard library copies as `tomllib`: its
compiled build parses the same files about 3x faster and imports in a third of the time
(the catalogue, ground truth and layout are read on every `utamp plan`).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import tomli

from utamp_gym.errors import SceneError

#: bound (m) on every coordinate and length in a scene or catalogue file: a kitchen table
MAX_COORD = 10.0
#: bounds (kg) on an object's mass: a gram to a tonne
MIN_MASS, MAX_MASS = 1e-3, 1000.0
#: object, slot, space, type and member names: also PDDL symbols
NAME = re.compile(r"[a-z][a-z0-9-]*")
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]{1,60}")


def show(value: Any) -> str:
    """A short one-line repr of a file value for an error message."""
    try:
        text = repr(value)
    except ValueError:  # holds an int beyond Python's int-to-str digit limit
        return "a value too large to show"
    return text if len(text) <= 60 else text[:57] + "..."


def key(parent: str, name: str) -> str:
    """Field path of table key `name` under `parent` (quoted when not a bare TOML key)."""
    part = name if _BARE_KEY.fullmatch(name) else json.dumps(name[:60])
    return f"{parent}.{part}" if parent else part


def read_toml(path: str | Path, what: str) -> dict[str, Any]:
    """Parse a TOML file read as UTF-8 (a leading byte-order mark is allowed)."""
    file = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise SceneError(f"cannot read {what}: {exc.strerror or exc}", file=file) from exc
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(
            f"not UTF-8 text: byte 0x{raw[exc.start]:02x} at offset {exc.start}", file=file
        ) from exc
    try:
        return tomli.loads(text)
    except tomli.TOMLDecodeError as exc:
        raise SceneError(f"invalid TOML: {exc}", file=file) from exc
    except RecursionError as exc:
        raise SceneError("invalid TOML: values nested too deeply", file=file) from exc
    except ValueError as exc:  # an integer literal beyond Python's int-from-str digit limit
        raise SceneError("invalid TOML: a number literal too long to read", file=file) from exc


def table(value: Any, file: str, path: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise SceneError(f"expected a table, got {show(value)}", file=file, field=path)
    return value


def tables(value: Any, file: str, path: str) -> list[Mapping[str, Any]]:
    """An array of tables (``[[path]]``); a non-table entry is named by its index."""
    if not isinstance(value, list):
        raise SceneError(
            f"expected an array of tables ([[{path}]]), got {show(value)}", file=file, field=path
        )
    return [table(v, file, f"{path}[{i}]") for i, v in enumerate(value)]


def need(d: Mapping[str, Any], name: str, file: str, path: str) -> Any:
    """The value of required key `name` of the table at `path`."""
    if name not in d:
        raise SceneError("missing required field", file=file, field=key(path, name))
    return d[name]


def known_keys(d: Mapping[str, Any], valid: Iterable[str], file: str, path: str) -> None:
    """Reject keys of the table at `path` that are not in `valid`."""
    valid = sorted(valid)
    unknown = sorted(k for k in d if k not in valid)
    if unknown:
        raise SceneError(
            f"unknown field; valid: {', '.join(valid)}", file=file, field=key(path, unknown[0])
        )


def text(value: Any, file: str, path: str, *, empty: bool = True) -> str:
    if not isinstance(value, str) or (not empty and not value.strip()):
        kind = "a string" if empty else "a non-empty string"
        raise SceneError(f"expected {kind}, got {show(value)}", file=file, field=path)
    return value


def boolean(value: Any, file: str, path: str) -> bool:
    """A real TOML boolean: ``"false"`` or ``0`` is an error, not a truthy value."""
    if not isinstance(value, bool):
        raise SceneError(
            f"expected true or false (unquoted), got {show(value)}", file=file, field=path
        )
    return value


def name(value: Any, file: str, path: str) -> str:
    if not isinstance(value, str) or not NAME.fullmatch(value):
        raise SceneError(
            f"{show(value)} is not a valid name "
            "(lower-case letters, digits and '-', starting with a letter)",
            file=file,
            field=path,
        )
    return value


def choice(value: Any, valid: Iterable[str], file: str, path: str) -> str:
    valid = tuple(valid)
    if not isinstance(value, str) or value not in valid:
        raise SceneError(f"{show(value)} is not one of {', '.join(valid)}", file=file, field=path)
    return value


def number(
    value: Any,
    file: str,
    path: str,
    *,
    positive: bool = False,
    lo: float = -math.inf,
    hi: float = math.inf,
) -> float:
    """A finite number in [lo, hi] (and > 0 if `positive`); booleans are not numbers."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise SceneError(f"expected a number, got {show(value)}", file=file, field=path)
    try:
        x = float(value)
    except OverflowError:
        x = math.inf if value > 0 else -math.inf
    if not math.isfinite(x):
        raise SceneError(f"expected a finite number, got {show(value)}", file=file, field=path)
    if positive and x <= 0:
        raise SceneError(f"must be > 0, got {show(value)}", file=file, field=path)
    if not lo <= x <= hi:
        low = "(0" if positive and lo <= 0 else f"[{lo:g}"
        raise SceneError(f"must lie in {low}, {hi:g}], got {show(value)}", file=file, field=path)
    return x


def vec(
    value: Any,
    n: int,
    file: str,
    path: str,
    *,
    positive: bool = False,
    lo: float = -MAX_COORD,
    hi: float = MAX_COORD,
) -> tuple[float, ...]:
    """A list of `n` finite numbers in [lo, hi] (metres by default; each > 0 if `positive`)."""
    if not isinstance(value, list) or len(value) != n:
        raise SceneError(
            f"expected a list of {n} numbers, got {show(value)}", file=file, field=path
        )
    return tuple(
        number(v, file, f"{path}[{i}]", positive=positive, lo=lo, hi=hi)
        for i, v in enumerate(value)
    )


def bounds(
    d: Mapping[str, Any], n: int, file: str, path: str, *, min_extent: float = 0.0
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Keys `min` and `max` of the table at `path`: `n`-vectors, max above min by > `min_extent`."""
    lo = vec(need(d, "min", file, path), n, file, f"{path}.min")
    hi = vec(need(d, "max", file, path), n, file, f"{path}.max")
    for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
        if b - a <= min_extent:
            at_least = f" by more than {min_extent:g}" if min_extent else ""
            raise SceneError(
                f"must be above {path}.min[{i}] = {a:g}{at_least}, got {b:g}",
                file=file,
                field=f"{path}.max[{i}]",
            )
    return lo, hi


__all__ = [
    "MAX_COORD",
    "MAX_MASS",
    "MIN_MASS",
    "NAME",
    "boolean",
    "bounds",
    "choice",
    "key",
    "known_keys",
    "name",
    "need",
    "number",
    "read_toml",
    "show",
    "table",
    "tables",
    "text",
    "vec",
]
