"""Object types: the physical attributes a perception model would report.

A type has members (body, handle, edges, ...) given as boxes parallel to the
object's own bounding box, per-part surface attributes, mass, material and
robustness. Types come from `assets/objects/*.toml` or from a scene file.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

from utamp_gym.errors import SceneError, UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene.fields import (
    MAX_MASS,
    MIN_MASS,
    boolean,
    bounds,
    key,
    known_keys,
    read_toml,
    text,
    vec,
)
from utamp_gym.scene.fields import choice as _choice
from utamp_gym.scene.fields import name as valid_name
from utamp_gym.scene.fields import need as _need
from utamp_gym.scene.fields import number as _number
from utamp_gym.scene.fields import table as _table
from utamp_gym.scene.geometry import PARTS, SIDES, Box

SHAPES = ("flat", "round", "thin", "pointy", "open", "concave")
MEMBER_KINDS = ("body", "handle", "edge")
GEOMS = ("box", "cylinder")
ROBUSTNESS = ("fragile", "sturdy", "solid")


class Member(NamedTuple):
    """A rigidly attached member of an object, e.g. a mug's handle."""

    name: str
    kind: str
    box: Box
    geom: str = "box"


class PartAttrs(NamedTuple):
    """Surface attributes of one side of an object's bounding box."""

    shape: str
    size: tuple[float, float] | None = None
    food_surface: bool = False
    height: float | None = None  # z of the usable surface (object frame), e.g. a tray's floor
    center: tuple[float, float] | None = None  # xy centre of the usable surface (object frame)


def _union(members: Mapping[str, Member]) -> Box:
    return _union_of(tuple(m.box for m in members.values()))


@lru_cache(maxsize=16_384)
def _union_of(boxes: tuple[Box, ...]) -> Box:
    """The box around `boxes` (cached: rules and the scene generator ask for bounding boxes
    many times)."""
    out = boxes[0]
    for b in boxes[1:]:
        out = out.union(b)
    return out


class ObjectType(NamedTuple):
    """Physical description of a kind of object."""

    name: str
    mass: float
    material: str
    robustness: str
    members: Mapping[str, Member]
    parts: Mapping[str, PartAttrs]
    movable: bool = True
    description: str = ""
    extra: Mapping[str, Any] = MappingProxyType({})  # read-only, so sharing it is safe

    @property
    def bbox(self) -> Box:
        """The object's bounding box: the union of its members' boxes."""
        return _union(self.members)

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
        return self._replace(parts=dict(parts))


TYPE_FIELDS = ("description", "mass", "material", "robustness", "movable", "members", "parts")
#: optional type attributes kept in `ObjectType.extra` (not used by the affordance rules)
EXTRA_FIELDS = ("rgba",)
MEMBER_FIELDS = ("kind", "geom", "min", "max")
PART_FIELDS = ("shape", "size", "food_surface", "height", "center")
#: smallest extent (m) of a member box along any axis
MIN_EXTENT = 1e-3
_TOL = 1e-6


def _members(value: Any, file: str, path: str) -> dict[str, Member]:
    members_raw = _table(value, file, path)
    if not members_raw:
        raise SceneError("expected a non-empty table of members", file=file, field=path)
    members: dict[str, Member] = {}
    for mname, m in members_raw.items():
        mpath = key(path, mname)
        valid_name(mname, file, mpath)
        m = _table(m, file, mpath)
        known_keys(m, MEMBER_FIELDS, file, mpath)
        lo, hi = bounds(m, 3, file, mpath, min_extent=MIN_EXTENT)
        members[mname] = Member(
            name=mname,
            kind=_choice(m.get("kind", "body"), MEMBER_KINDS, file, f"{mpath}.kind"),
            box=Box(lo, hi),  # type: ignore[arg-type]
            geom=_choice(m.get("geom", "box"), GEOMS, file, f"{mpath}.geom"),
        )
    if sum(m.kind == "body" for m in members.values()) != 1:
        raise SceneError("exactly one member must have kind 'body'", file=file, field=path)
    return members


def _part(p: Any, side: str, bbox: Box, file: str, path: str) -> PartAttrs:
    """One part's attributes; its usable surface must lie on the bounding box's face."""
    p = _table(p, file, path)
    known_keys(p, PART_FIELDS, file, path)
    size, center, height = p.get("size"), p.get("center"), p.get("height")
    face = bbox.face_size(side) if size is not None or center is not None else (0.0, 0.0)
    if size is not None:
        size = vec(size, 2, file, f"{path}.size", positive=True)
        if any(s > f + _TOL for s, f in zip(size, face, strict=True)):
            raise SceneError(
                f"{list(size)} exceeds the bounding-box face {[round(f, 6) for f in face]}",
                file=file,
                field=f"{path}.size",
            )
    if center is not None:
        center = vec(center, 2, file, f"{path}.center")
        extent = size if size is not None else face
        if side in ("on", "under") and not all(
            bbox.min[i] - _TOL <= center[i] - extent[i] / 2
            and center[i] + extent[i] / 2 <= bbox.max[i] + _TOL
            for i in (0, 1)
        ):
            raise SceneError(
                f"the surface at {list(center)} of size {list(extent)} leaves the bounding box",
                file=file,
                field=f"{path}.center",
            )
    if height is not None:
        height = _number(height, file, f"{path}.height", lo=bbox.min[2], hi=bbox.max[2])
    return PartAttrs(
        shape=_choice(_need(p, "shape", file, path), SHAPES, file, f"{path}.shape"),
        size=size,  # type: ignore[arg-type]
        food_surface=boolean(p.get("food_surface", False), file, f"{path}.food_surface"),
        height=height,
        center=center,  # type: ignore[arg-type]
    )


def parse_type(
    name: str, data: Mapping[str, Any], file: str, path: str | None = None
) -> ObjectType:
    """Build an ObjectType from its TOML table; errors name the file and the field."""
    path = path or key("types", name)
    valid_name(name, file, path)
    data = _table(data, file, path)
    known_keys(data, (*TYPE_FIELDS, *EXTRA_FIELDS), file, path)
    members = _members(_need(data, "members", file, path), file, f"{path}.members")
    bbox = _union(members)
    parts_raw = _table(_need(data, "parts", file, path), file, f"{path}.parts")
    parts: dict[str, PartAttrs] = {}
    for pname, p in parts_raw.items():
        ppath = key(f"{path}.parts", pname)
        parts[pname] = _part(p, _choice(pname, SIDES, file, ppath), bbox, file, ppath)
    missing = [s for s in SIDES if s not in parts]
    if missing:
        raise SceneError(f"missing parts {', '.join(missing)}", file=file, field=f"{path}.parts")
    extra: dict[str, Any] = {}
    if "rgba" in data:
        extra["rgba"] = vec(data["rgba"], 4, file, f"{path}.rgba", lo=0.0, hi=1.0)
    return ObjectType(
        name=name,
        mass=_number(
            _need(data, "mass", file, path),
            file,
            f"{path}.mass",
            positive=True,
            lo=MIN_MASS,
            hi=MAX_MASS,
        ),
        material=text(_need(data, "material", file, path), file, f"{path}.material", empty=False),
        robustness=_choice(
            _need(data, "robustness", file, path), ROBUSTNESS, file, f"{path}.robustness"
        ),
        members=members,
        parts=parts,
        movable=boolean(data.get("movable", True), file, f"{path}.movable"),
        description=text(data.get("description", ""), file, f"{path}.description"),
        extra=extra,
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
    out.update({k: list(v) if isinstance(v, tuple) else v for k, v in t.extra.items()})
    return out


class Catalogue:
    """A set of object types, looked up by name with a helpful error."""

    __slots__ = ("types",)
    types: Mapping[str, ObjectType]

    def __init__(self, types: Mapping[str, ObjectType]) -> None:
        object.__setattr__(self, "types", types)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"cannot assign to field {name!r}: a Catalogue is immutable")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Catalogue) and self.types == other.types

    __hash__ = None  # type: ignore[assignment]  # `types` is not hashable

    def __repr__(self) -> str:
        return f"Catalogue(types={self.types!r})"

    def __reduce__(self) -> tuple[type[Catalogue], tuple[Mapping[str, ObjectType]]]:
        return Catalogue, (self.types,)

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
    file = str(path if path is not None else asset_path("objects", "kitchen.toml"))
    data = read_toml(file, "catalogue file")
    known_keys(data, ("types",), file, "")
    types_raw = _table(_need(data, "types", file, ""), file, "types")
    if not types_raw:
        raise SceneError("expected at least one object type", file=file, field="types")
    return Catalogue({n: parse_type(n, d, file) for n, d in types_raw.items()})


__all__ = [
    "EXTRA_FIELDS",
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
