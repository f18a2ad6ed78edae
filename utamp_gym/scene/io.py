"""Read, validate and write scene files (TOML).

Every problem is reported as a `SceneError` naming the file and the field, e.g.
``scenes/my.toml: field 'objects[2].on': unknown support 'shelf'; valid: mug, slot1, ...``.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import tomli_w

from utamp_gym.errors import SceneError
from utamp_gym.scene.catalogue import Catalogue, load_catalogue, parse_type, type_to_dict, vec
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.model import ORIENTATIONS, Scene, SceneObject, Slot, Space

RESERVED = frozenset({"hand", "air", "workspace", "table"})
_NAME = re.compile(r"^[a-z][a-z0-9-]*$")


def _name(value: Any, file: str, path: str) -> str:
    if not isinstance(value, str) or not _NAME.match(value):
        raise SceneError(
            f"{value!r} is not a valid name "
            "(lower-case letters, digits and '-', starting with a letter)",
            file=file,
            field=path,
        )
    if value in RESERVED:
        raise SceneError(
            f"'{value}' is reserved ({', '.join(sorted(RESERVED))})", file=file, field=path
        )
    return value


def _list(data: Mapping[str, Any], key: str, file: str) -> list[Mapping[str, Any]]:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
        raise SceneError("expected an array of tables ([[...]])", file=file, field=key)
    return value


def scene_from_dict(
    data: Mapping[str, Any], *, file: str = "<scene>", catalogue: Catalogue | None = None
) -> Scene:
    """Validate a parsed scene table and build a `Scene`."""
    base = catalogue if catalogue is not None else load_catalogue()
    known = {
        "name",
        "description",
        "workspace",
        "table",
        "slots",
        "spaces",
        "objects",
        "types",
        "goal_base",
    }
    unknown = sorted(set(data) - known)
    if unknown:
        raise SceneError(
            f"unknown field(s); valid: {', '.join(sorted(known))}", file=file, field=unknown[0]
        )
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise SceneError("expected a non-empty string", file=file, field="name")

    types_raw = data.get("types", {})
    if not isinstance(types_raw, Mapping):
        raise SceneError("expected a table of object types", file=file, field="types")
    custom = {n: parse_type(n, d, file, f"types.{n}") for n, d in types_raw.items()}
    cat = base.merged(custom)

    ws = data.get("workspace")
    if not isinstance(ws, Mapping):
        raise SceneError("missing or not a table", file=file, field="workspace")
    ws_min = vec(ws.get("min"), 3, file, "workspace.min")
    ws_max = vec(ws.get("max"), 3, file, "workspace.max")
    if any(a >= b for a, b in zip(ws_min, ws_max, strict=True)):
        raise SceneError("min must be below max on every axis", file=file, field="workspace")

    table = data.get("table", {})
    table_type = table.get("type", "kitchen-table") if isinstance(table, Mapping) else None
    if table_type not in cat:
        raise SceneError(
            f"unknown table type {table_type!r}; valid: {', '.join(sorted(cat.types))}",
            file=file,
            field="table.type",
        )
    if cat[table_type].movable:
        raise SceneError(
            f"table type '{table_type}' must have movable = false", file=file, field="table.type"
        )
    top = cat[table_type].bbox

    slots: list[Slot] = []
    for i, s in enumerate(_list(data, "slots", file)):
        p = f"slots[{i}]"
        pos = vec(s.get("position"), 2, file, f"{p}.position")
        if "size" in s:
            size = vec(s.get("size"), 2, file, f"{p}.size", positive=True)
            lo = [c - d / 2 for c, d in zip(pos, size, strict=True)]
            hi = [c + d / 2 for c, d in zip(pos, size, strict=True)]
        else:
            lo = list(vec(s.get("min"), 2, file, f"{p}.min"))
            hi = list(vec(s.get("max"), 2, file, f"{p}.max"))
            if any(a >= b for a, b in zip(lo, hi, strict=True)):
                raise SceneError("min must be below max", file=file, field=p)
        region = Box((float(lo[0]), float(lo[1]), 0.0), (float(hi[0]), float(hi[1]), 0.0))
        slot = Slot(_name(s.get("name"), file, f"{p}.name"), pos, region)  # type: ignore[arg-type]
        if not region.contains_xy(Box((*pos, 0.0), (*pos, 0.0))):
            raise SceneError(
                "position lies outside the slot region", file=file, field=f"{p}.position"
            )
        if not top.contains_xy(slot.box):
            raise SceneError("slot region lies outside the table top", file=file, field=p)
        for other in slots:
            if other.box.overlaps_xy(slot.box):
                raise SceneError(f"slot region overlaps slot '{other.name}'", file=file, field=p)
        slots.append(slot)
    if not slots:
        raise SceneError("a scene needs at least one slot", file=file, field="slots")
    slot_names = {s.name for s in slots}

    spaces: list[Space] = []
    for i, s in enumerate(_list(data, "spaces", file)):
        p = f"spaces[{i}]"
        slot_name = s.get("slot")
        if slot_name not in slot_names:
            raise SceneError(
                f"unknown slot {slot_name!r}; valid: {', '.join(sorted(slot_names))}",
                file=file,
                field=f"{p}.slot",
            )
        space = Space(
            _name(s.get("name"), file, f"{p}.name"),
            slot_name,
            vec(s.get("position"), 2, file, f"{p}.position"),  # type: ignore[arg-type]
            vec(s.get("size"), 2, file, f"{p}.size", positive=True),  # type: ignore[arg-type]
        )
        slot_box = next(sl.box for sl in slots if sl.name == slot_name)
        if not slot_box.contains_xy(space.box, tol=1e-6):
            raise SceneError(f"space lies outside its slot '{slot_name}'", file=file, field=p)
        spaces.append(space)

    objects: list[SceneObject] = []
    seen = set(slot_names) | {s.name for s in spaces}
    raw_objects = _list(data, "objects", file)
    object_names = [o.get("name") for o in raw_objects]
    for i, o in enumerate(raw_objects):
        p = f"objects[{i}]"
        oname = _name(o.get("name"), file, f"{p}.name")
        if oname in seen:
            raise SceneError(f"duplicate name '{oname}'", file=file, field=f"{p}.name")
        seen.add(oname)
        otype = o.get("type")
        if otype not in cat:
            raise SceneError(
                f"unknown object type {otype!r}; valid: {', '.join(sorted(cat.types))}",
                file=file,
                field=f"{p}.type",
            )
        if not cat[otype].movable:
            raise SceneError(
                f"type '{otype}' is not movable (a table?)", file=file, field=f"{p}.type"
            )
        on = o.get("on")
        supports = sorted(
            slot_names | {n for n in object_names if isinstance(n, str) and n != oname}
        )
        if on not in supports:
            raise SceneError(
                f"unknown support {on!r}; valid: {', '.join(supports)}", file=file, field=f"{p}.on"
            )
        orientation = o.get("orientation", "upright")
        if orientation not in ORIENTATIONS:
            raise SceneError(
                f"{orientation!r} is not one of {', '.join(ORIENTATIONS)}",
                file=file,
                field=f"{p}.orientation",
            )
        position = o.get("position")
        if position is not None:
            if on not in slot_names:
                raise SceneError(
                    "position is only allowed for objects standing on a slot",
                    file=file,
                    field=f"{p}.position",
                )
            position = vec(position, 2, file, f"{p}.position")
        unknown = sorted(set(o) - {"name", "type", "on", "orientation", "position"})
        if unknown:
            raise SceneError(
                "unknown field; valid: name, type, on, orientation, position",
                file=file,
                field=f"{p}.{unknown[0]}",
            )
        objects.append(SceneObject(oname, otype, on, orientation, position))  # type: ignore[arg-type]

    _check_supports(objects, slot_names, file)
    goal_base = data.get("goal_base")
    if goal_base is not None and goal_base not in {o.name for o in objects}:
        raise SceneError(
            f"unknown object {goal_base!r}; valid: {', '.join(o.name for o in objects)}",
            file=file,
            field="goal_base",
        )
    scene = Scene(
        name=name,
        catalogue=cat,
        table_type=table_type,
        workspace=Box(ws_min, ws_max),  # type: ignore[arg-type]
        slots=tuple(slots),
        spaces=tuple(spaces),
        objects=tuple(objects),
        custom_types=custom,
        description=str(data.get("description", "")),
        source=file,
        goal_base=goal_base,
    )
    _check_footprints(scene, file)
    return scene


def _check_supports(objects: list[SceneObject], slots: set[str], file: str) -> None:
    holder: dict[str, str] = {}
    for i, o in enumerate(objects):
        if o.on in holder:
            raise SceneError(
                f"'{o.on}' already supports '{holder[o.on]}'; one object per support",
                file=file,
                field=f"objects[{i}].on",
            )
        holder[o.on] = o.name
    by_name = {o.name: o for o in objects}
    for i, o in enumerate(objects):
        seen, cur = {o.name}, o.on
        while cur not in slots:
            if cur in seen:
                raise SceneError(
                    f"support cycle through '{cur}'", file=file, field=f"objects[{i}].on"
                )
            seen.add(cur)
            cur = by_name[cur].on


def _check_footprints(scene: Scene, file: str) -> None:
    for slot_name, chain in scene.stacks.items():
        slot_box = scene.slot(slot_name).box
        for name in chain:
            if not slot_box.contains_xy(scene.world_box(name), tol=1e-6):
                idx = scene.object_names.index(name)
                raise SceneError(
                    f"'{name}' does not fit inside slot '{slot_name}'",
                    file=file,
                    field=f"objects[{idx}]",
                )


def load_scene(path: str | Path, *, catalogue: Catalogue | None = None) -> Scene:
    """Load and validate a scene file."""
    file = Path(path)
    try:
        text = file.read_text()
    except OSError as exc:
        raise SceneError(f"cannot read scene file: {exc.strerror}", file=str(file)) from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"invalid TOML: {exc}", file=str(file)) from exc
    return scene_from_dict(data, file=str(file), catalogue=catalogue)


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """Plain-data form of a scene; `scene_from_dict(scene_to_dict(s))` rebuilds it."""
    out: dict[str, Any] = {"name": scene.name}
    if scene.description:
        out["description"] = scene.description
    if scene.goal_base is not None:
        out["goal_base"] = scene.goal_base
    out["workspace"] = {"min": list(scene.workspace.min), "max": list(scene.workspace.max)}
    out["table"] = {"type": scene.table_type}
    out["slots"] = [
        {
            "name": s.name,
            "position": list(s.position),
            "min": list(s.region.min[:2]),
            "max": list(s.region.max[:2]),
        }
        for s in scene.slots
    ]
    if scene.spaces:
        out["spaces"] = [
            {"name": s.name, "slot": s.slot, "position": list(s.position), "size": list(s.size)}
            for s in scene.spaces
        ]
    objs = []
    for o in scene.objects:
        entry: dict[str, Any] = {
            "name": o.name,
            "type": o.type,
            "on": o.on,
            "orientation": o.orientation,
        }
        if o.position is not None:
            entry["position"] = list(o.position)
        objs.append(entry)
    out["objects"] = objs
    if scene.custom_types:
        out["types"] = {n: type_to_dict(t) for n, t in scene.custom_types.items()}
    return out


def scene_to_toml(scene: Scene) -> str:
    return tomli_w.dumps(scene_to_dict(scene))


__all__ = ["load_scene", "scene_from_dict", "scene_to_dict", "scene_to_toml"]
