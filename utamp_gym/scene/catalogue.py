"""Object types: the physical attributes a perception model would report.

A type has members (body, handle, edges, ...) given as boxes parallel to the
object's own bounding box, per-part surface attributes, mass, material and
robustness. Types come from `assets/objects/*.toml` or from a scene file.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from utamp_gym.errors import SceneError, UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene.geometry import PARTS, SIDES, Box

SHAPES = ("flat", "round", "thin", "pointy", "open", "concave")
MEMBER_KINDS = ("body", "handle", "edge")
GEOMS = ("box", "cylinder")
ROBUSTNESS = ("fragile", "sturdy", "solid")


@dataclass(frozen=True)
class Member:
    """A rigidly attached member of an object, e.g. a mug's handle."""

    name: str
    kind: str
    box: Box
    geom: str = "box"


@dataclass(frozen=True)
class PartAttrs:
    """Surface attributes of one side of an object's bounding box."""

    shape: str
    size: tuple[float, float] | None = None
    food_surface: bool = False
    height: float | None = None  # z of the usable surface (object frame), e.g. a tray's floor
    center: tuple[float, float] | None = None  # xy centre of the usable surface (object frame)


@dataclass(frozen=True)
class ObjectType:
    """Physical description of a kind of object."""

    name: str
    mass: float
    material: str
    robustness: str
    members: Mapping[str, Member]
    parts: Mapping[str, PartAttrs]
    movable: bool = True
    description: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def bbox(self) -> Box:
        """The object's bounding box: the union of its members' boxes."""
        boxes = [m.box for m in self.members.values()]
        out = boxes[0]
        for b in boxes[1:]:
            out = out.union(b)
        return out

    @property
    def body(self) -> Member:
        for m in self.members.values():
            if m.kind == "body":
                return m
        raise SceneError(f"type '{self.name}' has no body member")

    def surface_size(self, part: str) -> tuple[float, float]:
        """Usable extent of a face: the declared size, else the bounding-box face."""
        attrs = self.parts[part]
        return attrs.size if attrs.size is not None else self.bbox.face_size(part)

    def surface_height(self, part: str) -> float:
        """Height of a part's usable surface above (on) or below (under) the origin."""
        attrs = self.parts[part]
        if attrs.height is not None:
            return attrs.height
        return self.bbox.max[2] if part == "on" else self.bbox.min[2]

    def surface_center(self, part: str) -> tuple[float, float]:
        """xy centre of a part's usable surface in the object frame."""
        attrs = self.parts[part]
        if attrs.center is not None:
            return attrs.center
        return self.bbox.center_xy

    def with_parts(self, parts: Mapping[str, PartAttrs]) -> ObjectType:
        return replace(self, parts=dict(parts))


def _need(d: Mapping[str, Any], key: str, file: str, path: str) -> Any:
    if key not in d:
        raise SceneError("missing required field", file=file, field=f"{path}.{key}")
    return d[key]


def _number(value: Any, file: str, path: str, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise SceneError(f"expected a number, got {value!r}", file=file, field=path)
    if positive and value <= 0:
        raise SceneError(f"must be > 0, got {value!r}", file=file, field=path)
    return float(value)


def vec(value: Any, n: int, file: str, path: str, *, positive: bool = False) -> tuple[float, ...]:
    """A list of `n` numbers (each > 0 if `positive`); errors name the file and the field."""
    if not isinstance(value, list) or len(value) != n:
        raise SceneError(f"expected a list of {n} numbers, got {value!r}", file=file, field=path)
    return tuple(_number(v, file, f"{path}[{i}]", positive=positive) for i, v in enumerate(value))


def _choice(value: Any, valid: tuple[str, ...], file: str, path: str) -> str:
    if value not in valid:
        raise SceneError(f"{value!r} is not one of {', '.join(valid)}", file=file, field=path)
    return str(value)


def parse_type(
    name: str, data: Mapping[str, Any], file: str, path: str | None = None
) -> ObjectType:
    """Build an ObjectType from its TOML table; errors name the file and the field."""
    path = path or f"types.{name}"
    if not isinstance(data, Mapping):
        raise SceneError("expected a table", file=file, field=path)
    members_raw = _need(data, "members", file, path)
    if not isinstance(members_raw, Mapping) or not members_raw:
        raise SceneError(
            "expected a non-empty table of members", file=file, field=f"{path}.members"
        )
    members: dict[str, Member] = {}
    for mname, m in members_raw.items():
        mpath = f"{path}.members.{mname}"
        if not isinstance(m, Mapping):
            raise SceneError("expected a table", file=file, field=mpath)
        lo = vec(_need(m, "min", file, mpath), 3, file, f"{mpath}.min")
        hi = vec(_need(m, "max", file, mpath), 3, file, f"{mpath}.max")
        if any(a >= b for a, b in zip(lo, hi, strict=True)):
            raise SceneError(f"min {lo} must be below max {hi}", file=file, field=mpath)
        members[mname] = Member(
            name=mname,
            kind=_choice(m.get("kind", "body"), MEMBER_KINDS, file, f"{mpath}.kind"),
            box=Box(lo, hi),
            geom=_choice(m.get("geom", "box"), GEOMS, file, f"{mpath}.geom"),
        )
    if sum(m.kind == "body" for m in members.values()) != 1:
        raise SceneError(
            "exactly one member must have kind 'body'", file=file, field=f"{path}.members"
        )
    parts_raw = _need(data, "parts", file, path)
    parts: dict[str, PartAttrs] = {}
    for pname, p in parts_raw.items():
        ppath = f"{path}.parts.{pname}"
        _choice(pname, SIDES, file, ppath)
        if not isinstance(p, Mapping):
            raise SceneError("expected a table", file=file, field=ppath)
        size, center, height = p.get("size"), p.get("center"), p.get("height")
        unknown = sorted(set(p) - {"shape", "size", "food_surface", "height", "center"})
        if unknown:
            raise SceneError(
                "unknown field; valid: shape, size, food_surface, height, center",
                file=file,
                field=f"{ppath}.{unknown[0]}",
            )
        parts[pname] = PartAttrs(
            shape=_choice(_need(p, "shape", file, ppath), SHAPES, file, f"{ppath}.shape"),
            size=None if size is None else vec(size, 2, file, f"{ppath}.size"),  # type: ignore[arg-type]
            food_surface=bool(p.get("food_surface", False)),
            height=None if height is None else _number(height, file, f"{ppath}.height"),
            center=None if center is None else vec(center, 2, file, f"{ppath}.center"),  # type: ignore[arg-type]
        )
    missing = [s for s in SIDES if s not in parts]
    if missing:
        raise SceneError(f"missing parts {', '.join(missing)}", file=file, field=f"{path}.parts")
    known = {"members", "parts", "mass", "material", "robustness", "movable", "description"}
    return ObjectType(
        name=name,
        mass=_number(_need(data, "mass", file, path), file, f"{path}.mass", positive=True),
        material=str(_need(data, "material", file, path)),
        robustness=_choice(
            _need(data, "robustness", file, path), ROBUSTNESS, file, f"{path}.robustness"
        ),
        members=members,
        parts=parts,
        movable=bool(data.get("movable", True)),
        description=str(data.get("description", "")),
        extra={k: v for k, v in data.items() if k not in known},
    )


def type_to_dict(t: ObjectType) -> dict[str, Any]:
    """Inverse of `parse_type` (for exporting scene files)."""
    out: dict[str, Any] = {
        "description": t.description,
        "mass": t.mass,
        "material": t.material,
        "robustness": t.robustness,
        "movable": t.movable,
        "members": {
            m.name: {"kind": m.kind, "geom": m.geom, "min": list(m.box.min), "max": list(m.box.max)}
            for m in t.members.values()
        },
        "parts": {},
    }
    for pname, p in t.parts.items():
        entry: dict[str, Any] = {"shape": p.shape}
        if p.size is not None:
            entry["size"] = list(p.size)
        if p.food_surface:
            entry["food_surface"] = True
        if p.height is not None:
            entry["height"] = p.height
        if p.center is not None:
            entry["center"] = list(p.center)
        out["parts"][pname] = entry
    return out


@dataclass(frozen=True)
class Catalogue:
    """A set of object types, looked up by name with a helpful error."""

    types: Mapping[str, ObjectType]

    def __getitem__(self, name: str) -> ObjectType:
        try:
            return self.types[name]
        except KeyError:
            raise UnknownNameError("object type", name, self.types) from None

    def __contains__(self, name: object) -> bool:
        return name in self.types

    def merged(self, extra: Mapping[str, ObjectType]) -> Catalogue:
        return Catalogue({**self.types, **extra})


def load_catalogue(path: str | Path | None = None) -> Catalogue:
    """Load a catalogue file (default: the packaged kitchen catalogue)."""
    file = Path(path) if path is not None else asset_path("objects", "kitchen.toml")
    try:
        data = tomllib.loads(file.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"invalid TOML: {exc}", file=str(file)) from exc
    types_raw = _need(data, "types", str(file), "")
    return Catalogue({n: parse_type(n, d, str(file)) for n, d in types_raw.items()})


__all__ = [
    "GEOMS",
    "MEMBER_KINDS",
    "PARTS",
    "ROBUSTNESS",
    "SHAPES",
    "Catalogue",
    "Member",
    "ObjectType",
    "PartAttrs",
    "load_catalogue",
    "parse_type",
    "type_to_dict",
]
