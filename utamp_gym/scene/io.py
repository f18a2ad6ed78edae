"""Read, validate and write scene files (TOML).

Every problem is reported as a `SceneError` naming the file and the field path, e.g.
``scenes/my.toml: field 'objects[2].on': unknown support 'shelf'; valid: mug, slot1, ...``;
values are type- and range-checked by `utamp_gym.scene.fields`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from utamp_gym.errors import SceneError
from utamp_gym.scene import fields as f
from utamp_gym.scene.catalogue import (
    Catalogue,
    ObjectType,
    load_catalogue,
    parse_type,
    type_to_dict,
)
from utamp_gym.scene.geometry import PARTS, Box
from utamp_gym.scene.model import ORIENTATIONS, Scene, SceneObject, Slot, Space
from utamp_gym.tasks.goal import CUSTOM, Goal, split_literal

#: the PDDL domains' constants (hand, air, workspace and the parts) and the table
RESERVED = frozenset({"hand", "air", "workspace", "table", *PARTS})
SCENE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_./-]{0,99}")
SCENE_FIELDS = (
    "name",
    "description",
    "workspace",
    "table",
    "slots",
    "spaces",
    "objects",
    "types",
    "goal_base",
    "goal",
)
GOAL_FIELDS = ("template", "params", "atoms")
SLOT_FIELDS = ("name", "position", "size", "min", "max")
SPACE_FIELDS = ("name", "slot", "position", "size")
OBJECT_FIELDS = ("name", "type", "on", "orientation", "position")


class _Names:
    """Slot, space and object names share one namespace (they are all PDDL objects)."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.where: dict[str, str] = {}

    def add(self, value: Any, path: str) -> str:
        name = f.name(value, self.file, path)
        if name in RESERVED:
            raise SceneError(
                f"'{name}' is reserved ({', '.join(sorted(RESERVED))})", file=self.file, field=path
            )
        if name in self.where:
            raise SceneError(
                f"duplicate name '{name}' (also {self.where[name]})", file=self.file, field=path
            )
        self.where[name] = path
        return name


def scene_from_dict(
    data: Mapping[str, Any], *, file: str = "<scene>", catalogue: Catalogue | None = None
) -> Scene:
    """Validate a parsed scene table and build a `Scene`."""
    base = catalogue if catalogue is not None else load_catalogue()
    data = f.table(data, file, "")
    f.known_keys(data, SCENE_FIELDS, file, "")
    name = f.text(f.need(data, "name", file, ""), file, "name", empty=False)
    if not SCENE_NAME.fullmatch(name):
        raise SceneError(
            f"{f.show(name)} is not a valid scene name (up to 100 letters, digits, "
            "'-', '_', '.' and '/', starting with a letter or digit; it names the PDDL problem)",
            file=file,
            field="name",
        )
    description = f.text(data.get("description", ""), file, "description")

    custom = _custom_types(data.get("types", {}), base, file)
    cat = base.merged(custom)
    ws = f.table(f.need(data, "workspace", file, ""), file, "workspace")
    f.known_keys(ws, ("min", "max"), file, "workspace")
    ws_min, ws_max = f.bounds(ws, 3, file, "workspace")
    table_type = _table_type(data.get("table", {}), cat, file)

    names = _Names(file)
    slots = _slots(data.get("slots", []), cat[table_type].bbox, names, file)
    spaces = _spaces(data.get("spaces", []), slots, names, file)
    objects = _objects(data.get("objects", []), cat, {s.name for s in slots}, names, file)
    _check_supports(objects, {s.name for s in slots}, file)
    _check_member_symbols(objects, cat, names, file)
    goal_base = data.get("goal_base")
    object_names = [o.name for o in objects]
    if goal_base is not None and (not isinstance(goal_base, str) or goal_base not in object_names):
        raise SceneError(
            f"unknown object {f.show(goal_base)}; valid: {', '.join(object_names)}",
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
        description=description,
        source=file,
        goal_base=goal_base,
    )
    _check_footprints(scene, file)
    if "goal" in data:
        scene = scene._replace(goal=_goal(data["goal"], scene, file))
    return scene


def _goal(value: Any, scene: Scene, file: str) -> Goal:
    """A scene file's ``[goal]``: a template (or composition ``a+b``) with its params, or
    ``atoms`` alone (a custom goal); atoms given with a template must be the template's."""
    g = f.table(value, file, "goal")
    f.known_keys(g, GOAL_FIELDS, file, "goal")
    atoms = g.get("atoms")
    if atoms is not None:
        if not isinstance(atoms, list) or not atoms:
            raise SceneError("want a non-empty list of literals", file=file, field="goal.atoms")
        symbols = _symbols(scene)
        for i, a in enumerate(atoms):
            try:
                if not isinstance(a, str):
                    raise ValueError(f"want a string such as '(oc on slot2 air)', got {a!r}")
                body = split_literal(a.lower())[1]
            except ValueError as exc:
                raise SceneError(str(exc), file=file, field=f"goal.atoms[{i}]") from None
            unknown = [x for x in body[1:-1].split()[1:] if x not in symbols]
            if unknown:
                raise SceneError(
                    f"unknown name '{unknown[0]}' in {a}", file=file, field=f"goal.atoms[{i}]"
                )
    name = g.get("template", CUSTOM if atoms is not None else None)
    if name is None:
        raise SceneError("give a template (with params) or atoms", file=file, field="goal")
    if name == CUSTOM:
        if atoms is None:
            raise SceneError("a custom goal needs atoms", file=file, field="goal.atoms")
        return Goal.make(CUSTOM, f.table(g.get("params", {}), file, "goal.params"), atoms)
    # Only a goal given by template needs the templates (and their attribute tables): off
    # `utamp plan`'s path for suite scenes.
    # lazy: keeps `utamp plan` from loading utamp_gym.tasks.templates
    from utamp_gym.tasks.templates import TEMPLATES, make_goal

    if not isinstance(name, str) or any(p not in TEMPLATES for p in name.split("+")):
        raise SceneError(
            f"unknown goal template {f.show(name)}; valid: {', '.join(TEMPLATES)} "
            "(or several joined by '+')",
            file=file,
            field="goal.template",
        )
    try:
        goal = make_goal(scene, name, f.table(g.get("params", {}), file, "goal.params"))
    except (ValueError, KeyError) as exc:
        raise SceneError(str(exc).strip("'\""), file=file, field="goal.params") from None
    if atoms is not None and tuple(a.lower() for a in atoms) != goal.literals:
        raise SceneError(
            f"differ from the literals of template '{name}' with these params",
            file=file,
            field="goal.atoms",
        )
    return goal


def _symbols(scene: Scene) -> set[str]:
    """Every name a goal literal may use: the scene's PDDL objects, the domains' constants."""
    out = {*RESERVED, *(s.name for s in scene.slots), *(s.name for s in scene.spaces)}
    for o in scene.objects:
        out.add(o.name)
        out |= {f"{o.name}-{m}" for m in scene.type_of(o.name).members}
    return {x.lower() for x in out}


def _custom_types(value: Any, base: Catalogue, file: str) -> dict[str, ObjectType]:
    types_raw = f.table(value, file, "types")
    for tname in types_raw:
        if tname in base:
            raise SceneError(
                f"type '{tname}' is already in the catalogue; give yours another name",
                file=file,
                field=f.key("types", tname),
            )
    return {n: parse_type(n, d, file) for n, d in types_raw.items()}


def _table_type(value: Any, cat: Catalogue, file: str) -> str:
    table = f.table(value, file, "table")
    f.known_keys(table, ("type",), file, "table")
    table_type = table.get("type", "kitchen-table")
    if not isinstance(table_type, str) or table_type not in cat:
        raise SceneError(
            f"unknown table type {f.show(table_type)}; valid: {', '.join(sorted(cat.types))}",
            file=file,
            field="table.type",
        )
    if cat[table_type].movable:
        raise SceneError(
            f"table type '{table_type}' must have movable = false", file=file, field="table.type"
        )
    return table_type


def _slots(value: Any, top: Box, names: _Names, file: str) -> list[Slot]:
    slots: list[Slot] = []
    for i, s in enumerate(f.tables(value, file, "slots")):
        p = f"slots[{i}]"
        f.known_keys(s, SLOT_FIELDS, file, p)
        name = names.add(f.need(s, "name", file, p), f"{p}.name")
        pos = f.vec(f.need(s, "position", file, p), 2, file, f"{p}.position")
        if "size" in s:
            if "min" in s or "max" in s:
                raise SceneError(
                    "give either size or min and max, not both", file=file, field=f"{p}.size"
                )
            size = f.vec(s["size"], 2, file, f"{p}.size", positive=True)
            lo = tuple(c - d / 2 for c, d in zip(pos, size, strict=True))
            hi = tuple(c + d / 2 for c, d in zip(pos, size, strict=True))
        else:
            lo, hi = f.bounds(s, 2, file, p)
        slot = Slot(name, pos, Box((*lo, 0.0), (*hi, 0.0)))  # type: ignore[arg-type]
        if not slot.region.contains_xy(Box((*pos, 0.0), (*pos, 0.0))):
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
    return slots


def _spaces(value: Any, slots: list[Slot], names: _Names, file: str) -> list[Space]:
    by_name = {s.name: s for s in slots}
    spaces: list[Space] = []
    for i, s in enumerate(f.tables(value, file, "spaces")):
        p = f"spaces[{i}]"
        f.known_keys(s, SPACE_FIELDS, file, p)
        name = names.add(f.need(s, "name", file, p), f"{p}.name")
        slot_name = f.need(s, "slot", file, p)
        if not isinstance(slot_name, str) or slot_name not in by_name:
            raise SceneError(
                f"unknown slot {f.show(slot_name)}; valid: {', '.join(sorted(by_name))}",
                file=file,
                field=f"{p}.slot",
            )
        space = Space(
            name,
            slot_name,
            f.vec(f.need(s, "position", file, p), 2, file, f"{p}.position"),  # type: ignore[arg-type]
            f.vec(f.need(s, "size", file, p), 2, file, f"{p}.size", positive=True),  # type: ignore[arg-type]
        )
        if not by_name[slot_name].box.contains_xy(space.box, tol=1e-6):
            raise SceneError(f"space lies outside its slot '{slot_name}'", file=file, field=p)
        spaces.append(space)
    return spaces


def _objects(
    value: Any, cat: Catalogue, slot_names: set[str], names: _Names, file: str
) -> list[SceneObject]:
    raw_objects = f.tables(value, file, "objects")
    if not raw_objects:
        raise SceneError(
            "a scene needs at least one object ([[objects]])", file=file, field="objects"
        )
    object_names = {  # supports may be objects listed later: take every well-formed name
        n for o in raw_objects if isinstance(n := o.get("name"), str) and f.NAME.fullmatch(n)
    }
    objects: list[SceneObject] = []
    for i, o in enumerate(raw_objects):
        p = f"objects[{i}]"
        f.known_keys(o, OBJECT_FIELDS, file, p)
        oname = names.add(f.need(o, "name", file, p), f"{p}.name")
        otype = f.need(o, "type", file, p)
        if not isinstance(otype, str) or otype not in cat:
            raise SceneError(
                f"unknown object type {f.show(otype)}; valid: {', '.join(sorted(cat.types))}",
                file=file,
                field=f"{p}.type",
            )
        if not cat[otype].movable:
            raise SceneError(
                f"type '{otype}' is not movable (a table?)", file=file, field=f"{p}.type"
            )
        on = f.need(o, "on", file, p)
        supports = sorted(slot_names | {n for n in object_names if n != oname})
        if not isinstance(on, str) or on not in supports:
            raise SceneError(
                f"unknown support {f.show(on)}; valid: {', '.join(supports)}",
                file=file,
                field=f"{p}.on",
            )
        orientation = f.choice(
            o.get("orientation", "upright"), ORIENTATIONS, file, f"{p}.orientation"
        )
        position = o.get("position")
        if position is not None:
            if on not in slot_names:
                raise SceneError(
                    "position is only allowed for objects standing on a slot",
                    file=file,
                    field=f"{p}.position",
                )
            position = f.vec(position, 2, file, f"{p}.position")
        objects.append(SceneObject(oname, otype, on, orientation, position))  # type: ignore[arg-type]
    return objects


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


def _check_member_symbols(
    objects: list[SceneObject], cat: Catalogue, names: _Names, file: str
) -> None:
    """Members are PDDL objects too, named ``<object>-<member>`` (`member_symbol`): no clash."""
    used = dict(names.where)
    for i, o in enumerate(objects):
        for member in cat[o.type].members:
            symbol = f"{o.name}-{member}"
            if symbol in used:
                raise SceneError(
                    f"member '{member}' of '{o.name}' is the PDDL object '{symbol}', "
                    f"which {used[symbol]} already names",
                    file=file,
                    field=f"objects[{i}].name",
                )
            used[symbol] = f"a member of objects[{i}]"


def _check_footprints(scene: Scene, file: str) -> None:
    for slot_name, chain in scene.stacks.items():
        slot_box = scene.slot(slot_name).box
        for name in chain:
            if not slot_box.contains_xy(scene.world_box(name), tol=1e-6):
                idx = scene.object_names.index(name)
                placed = scene.objects[idx].position is not None
                raise SceneError(
                    f"'{name}' does not fit inside slot '{slot_name}'",
                    file=file,
                    field=f"objects[{idx}].position" if placed else f"objects[{idx}]",
                )


def load_scene(path: str | Path, *, catalogue: Catalogue | None = None) -> Scene:
    """Load and validate a scene file (UTF-8 TOML)."""
    data = f.read_toml(path, "scene file")
    return scene_from_dict(data, file=str(path), catalogue=catalogue)


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
    if scene.goal is not None:
        out["goal"] = scene.goal.to_dict()
    return out


def scene_to_toml(scene: Scene) -> str:
    import tomli_w  # only for writing: off the path of loading scenes

    return tomli_w.dumps(scene_to_dict(scene))


__all__ = ["load_scene", "scene_from_dict", "scene_to_dict", "scene_to_toml"]
