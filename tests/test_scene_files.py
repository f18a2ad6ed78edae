"""Malformed scene and catalogue files: every one is a `SceneError` naming the file and field.

The audit: each case below is one malformed file derived from a valid scene (the demo
scene plus a space and a custom `plate` type standing on the tray) or from the packaged
catalogue. Loading it must raise `SceneError` whose message names the file and, for every
problem past the TOML syntax, the exact field path; `utamp scenes show FILE` must exit 2
with that message on one line.
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import pytest
import tomli_w
from scene_bases import base_catalogue, base_scene, plate_type

from utamp_gym.cli import main
from utamp_gym.errors import SceneError
from utamp_gym.scene import (
    load_catalogue,
    load_scene,
    scene_from_dict,
    scene_to_dict,
    scene_to_toml,
)
from utamp_gym.scene.io import RESERVED
from utamp_gym.symbolic.pddl import parse_domain
from utamp_gym.symbolic.problem import DOMAINS, domain_text

NAN, INF, HUGE = math.nan, math.inf, 10**400

Edit = Callable[[dict[str, Any]], bytes | None]


class Case(NamedTuple):
    id: str
    edit: Edit  # mutates the data in place, or returns the raw bytes of the file
    field: str | None  # the field the error must name (None: a file-level error)
    words: str = ""  # a phrase the message must contain


def _steps(path: str) -> list[str | int]:
    return [int(s) if s.isdigit() else s for s in re.findall(r"[^.\[\]]+", path)]


def _parent(data: dict[str, Any], path: str) -> tuple[Any, str | int]:
    *head, last = _steps(path)
    for s in head:
        data = data[s]
    return data, last


def at(path: str, value: Any) -> Edit:
    """Set the value at `path` (``objects[2].name``), creating nothing but the last key."""

    def edit(data: dict[str, Any]) -> None:
        parent, last = _parent(data, path)
        parent[last] = value

    return edit


def drop(path: str) -> Edit:
    def edit(data: dict[str, Any]) -> None:
        parent, last = _parent(data, path)
        del parent[last]

    return edit


def both(*edits: Edit) -> Edit:
    def edit(data: dict[str, Any]) -> None:
        for e in edits:
            e(data)

    return edit


def raw(content: bytes) -> Edit:
    return lambda data: content


def case(id: str, edit: Edit, field: str | None = "", words: str = "") -> Case:
    """A case; the field defaults to the path an `at`/`drop` edit names (given explicitly)."""
    return Case(id, edit, field, words)


TP = "types.plate"
SCENE_CASES = [
    # ---------------------------------------------------------------- the file itself
    case("non-utf8-latin1", raw('name = "café"\n'.encode("latin-1")), None, "UTF-8"),
    case("non-utf8-utf16", raw('name = "x"\n'.encode("utf-16")), None, "UTF-8"),
    case("invalid-toml", raw(b"name = [unclosed\n"), None, "invalid TOML"),
    case("huge-int-literal", raw(b"name = 'x'\nmass = " + b"9" * 5000 + b"\n"), None, "TOML"),
    case("deeply-nested", raw(b"x = " + b"[" * 3000 + b"]" * 3000 + b"\n"), None, "TOML"),
    case("empty-file", raw(b""), "name"),
    # ---------------------------------------------------------------- top level
    case("unknown-top-key", at("colour", "red"), "colour", "unknown field"),
    case("name-missing", drop("name"), "name"),
    case("name-number", at("name", 5), "name"),
    case("name-empty", at("name", "  "), "name"),
    case("name-with-spaces", at("name", "my kitchen"), "name", "valid scene name"),
    case("name-with-newline", at("name", "a\nb"), "name"),
    case("description-table", at("description", {"a": 1}), "description"),
    # ---------------------------------------------------------------- workspace
    case("workspace-missing", drop("workspace"), "workspace"),
    case("workspace-number", at("workspace", 5), "workspace"),
    case("workspace-min-short", at("workspace.min", [0, 0]), "workspace.min", "3 numbers"),
    case("workspace-min-nan", at("workspace.min[0]", NAN), "workspace.min[0]", "finite"),
    case("workspace-max-inf", at("workspace.max[2]", INF), "workspace.max[2]", "finite"),
    case("workspace-min-string", at("workspace.min[1]", "-0.6"), "workspace.min[1]", "number"),
    case("workspace-min-bool", at("workspace.min[0]", True), "workspace.min[0]", "number"),
    case("workspace-max-huge-int", at("workspace.max[0]", HUGE), "workspace.max[0]"),
    case("workspace-max-absurd", at("workspace.max[1]", 1e9), "workspace.max[1]"),
    case("workspace-min-above-max", at("workspace.min[0]", 0.9), "workspace.max[0]", "above"),
    case("workspace-unknown-key", at("workspace.centre", [0, 0, 0]), "workspace.centre"),
    # ---------------------------------------------------------------- table
    case("table-number", at("table", 5), "table"),
    case("table-type-unknown", at("table.type", "wok"), "table.type", "valid: cutting-board"),
    case("table-type-movable", at("table.type", "salt-shaker"), "table.type", "movable"),
    case("table-type-list", at("table.type", ["kitchen-table"]), "table.type"),
    case("table-unknown-key", at("table.colour", "oak"), "table.colour"),
    # ---------------------------------------------------------------- slots
    case("slots-number", at("slots", 5), "slots"),
    case("slots-empty", at("slots", []), "slots", "at least one slot"),
    case("slots-entry-number", at("slots[0]", 5), "slots[0]"),
    case("slot-name-missing", drop("slots[1].name"), "slots[1].name"),
    case("slot-name-invalid", at("slots[1].name", "Slot 2"), "slots[1].name"),
    case("slot-name-reserved", at("slots[1].name", "table"), "slots[1].name", "reserved"),
    case("slot-name-duplicate", at("slots[1].name", "slot1"), "slots[1].name", "duplicate"),
    case("slot-position-nan", at("slots[1].position[0]", NAN), "slots[1].position[0]"),
    case("slot-position-string", at("slots[1].position", "0.2, 0.38"), "slots[1].position"),
    case("slot-position-missing", drop("slots[1].position"), "slots[1].position"),
    case("slot-min-inf", at("slots[1].min[0]", -INF), "slots[1].min[0]"),
    case("slot-max-huge-int", at("slots[1].max[1]", HUGE), "slots[1].max[1]"),
    case("slot-min-above-max", at("slots[1].min[1]", 0.6), "slots[1].max[1]", "above"),
    case(
        "slot-size-negative",
        both(drop("slots[1].min"), drop("slots[1].max"), at("slots[1].size", [-0.4, 0.3])),
        "slots[1].size[0]",
        "> 0",
    ),
    case(
        "slot-size-zero",
        both(drop("slots[1].min"), drop("slots[1].max"), at("slots[1].size", [0.4, 0])),
        "slots[1].size[1]",
    ),
    case("slot-size-and-bounds", at("slots[1].size", [0.4, 0.3]), "slots[1].size", "either"),
    case("slot-outside-table", at("slots[1].max", [2.5, 0.52]), "slots[1]", "table top"),
    case("slot-overlap", at("slots[1].min", [0.04, 0.1]), "slots[1]", "overlaps"),
    case("slot-position-outside", at("slots[1].position", [0.6, 0.38]), "slots[1].position"),
    case("slot-unknown-key", at("slots[1].colour", "red"), "slots[1].colour"),
    # ---------------------------------------------------------------- spaces
    case("spaces-table", at("spaces", {"space1": {}}), "spaces"),
    case("space-slot-unknown", at("spaces[0].slot", "slot9"), "spaces[0].slot", "valid: slot1"),
    case("space-slot-list", at("spaces[0].slot", ["slot1"]), "spaces[0].slot"),
    case("space-size-negative", at("spaces[0].size[0]", -0.45), "spaces[0].size[0]"),
    case("space-size-nan", at("spaces[0].size[1]", NAN), "spaces[0].size[1]"),
    case("space-position-missing", drop("spaces[0].position"), "spaces[0].position"),
    case("space-name-is-slot", at("spaces[0].name", "slot2"), "spaces[0].name", "duplicate"),
    case(
        "space-name-duplicate",
        lambda d: d["spaces"].append(dict(d["spaces"][0])),
        "spaces[1].name",
        "duplicate",
    ),
    case("space-outside-slot", at("spaces[0].position", [0.9, 0.3]), "spaces[0]", "outside"),
    case("space-unknown-key", at("spaces[0].depth", 0.1), "spaces[0].depth"),
    # ---------------------------------------------------------------- objects
    case("objects-missing", drop("objects"), "objects", "at least one object"),
    case("objects-empty", at("objects", []), "objects", "at least one object"),
    case("objects-string", at("objects", "tray"), "objects"),
    case("object-entry-number", at("objects[2]", 5), "objects[2]"),
    case("object-name-missing", drop("objects[2].name"), "objects[2].name"),
    case("object-name-newline", at("objects[2].name", "board\n"), "objects[2].name"),
    case("object-name-duplicate", at("objects[2].name", "pan"), "objects[2].name", "duplicate"),
    case("object-name-is-slot", at("objects[2].name", "slot1"), "objects[2].name", "duplicate"),
    case("object-name-is-a-part", at("objects[2].name", "on"), "objects[2].name", "reserved"),
    case(
        "object-name-is-a-member-symbol",
        at("objects[2].name", "mug-body"),
        "objects[3].name",
        "objects[2].name already names",
    ),
    case("object-type-missing", drop("objects[2].type"), "objects[2].type"),
    case("object-type-number", at("objects[2].type", 3), "objects[2].type"),
    case("object-type-list", at("objects[2].type", ["cutting-board"]), "objects[2].type"),
    case("object-type-fixed", at("objects[2].type", "kitchen-table"), "objects[2].type", "movable"),
    case("object-on-table", at("objects[2].on", {"slot": "slot3"}), "objects[2].on"),
    case("object-on-itself", at("objects[2].on", "board"), "objects[2].on"),
    case("object-orientation-bool", at("objects[2].orientation", True), "objects[2].orientation"),
    case(
        "object-orientation-case",
        at("objects[3].orientation", "Inverted"),
        "objects[3].orientation",
    ),
    case("object-position-nan", at("objects[2].position", [NAN, -0.38]), "objects[2].position[0]"),
    case(
        "object-position-not-on-slot",
        at("objects[5].position", [0.5, 0.0]),
        "objects[5].position",
        "only allowed",
    ),
    case(
        "object-position-outside-slot",
        at("objects[2].position", [0.05, -0.38]),
        "objects[2].position",
        "does not fit",
    ),
    case("object-unknown-key", at("objects[2].colour", "red"), "objects[2].colour"),
    case("goal-base-list", at("goal_base", ["tray"]), "goal_base"),
    case("goal-base-slot", at("goal_base", "slot1"), "goal_base", "valid: tray"),
    # ---------------------------------------------------------------- custom types
    case("types-number", at("types", 5), "types"),
    case("type-number", at(TP, 5), TP),
    case(
        "type-name-invalid", lambda d: d["types"].update({"Plate!": plate_type()}), 'types."Plate!"'
    ),
    case(
        "type-shadows-catalogue",
        lambda d: d["types"].update({"salt-shaker": plate_type()}),
        "types.salt-shaker",
        "catalogue",
    ),
    case("mass-nan", at(f"{TP}.mass", NAN), f"{TP}.mass", "finite"),
    case("mass-inf", at(f"{TP}.mass", INF), f"{TP}.mass", "finite"),
    case("mass-negative", at(f"{TP}.mass", -1), f"{TP}.mass", "> 0"),
    case("mass-string", at(f"{TP}.mass", "0.4"), f"{TP}.mass", "number"),
    case("mass-huge-int", at(f"{TP}.mass", HUGE), f"{TP}.mass"),
    case("mass-absurd", at(f"{TP}.mass", 1e9), f"{TP}.mass", "[0.001, 1000]"),
    case("mass-tiny", at(f"{TP}.mass", 1e-300), f"{TP}.mass", "[0.001, 1000]"),
    case("mass-missing", drop(f"{TP}.mass"), f"{TP}.mass", "missing"),
    case("material-number", at(f"{TP}.material", 5), f"{TP}.material"),
    case("robustness-unknown", at(f"{TP}.robustness", "strong"), f"{TP}.robustness", "fragile"),
    case("movable-string", at(f"{TP}.movable", "false"), f"{TP}.movable", "true or false"),
    case("movable-int", at(f"{TP}.movable", 0), f"{TP}.movable"),
    case("type-description-list", at(f"{TP}.description", []), f"{TP}.description"),
    case("type-unknown-key", at(f"{TP}.moveable", False), f"{TP}.moveable", "unknown field"),
    case("rgba-short", at(f"{TP}.rgba", [1, 0, 0]), f"{TP}.rgba"),
    case("rgba-out-of-range", at(f"{TP}.rgba", [2, 0, 0, 1]), f"{TP}.rgba[0]"),
    case("members-missing", drop(f"{TP}.members"), f"{TP}.members"),
    case("members-empty", at(f"{TP}.members", {}), f"{TP}.members"),
    case("member-number", at(f"{TP}.members.body", 5), f"{TP}.members.body"),
    case("member-min-nan", at(f"{TP}.members.body.min[0]", NAN), f"{TP}.members.body.min[0]"),
    case("member-max-inf", at(f"{TP}.members.body.max[2]", INF), f"{TP}.members.body.max[2]"),
    case(
        "member-min-above-max", at(f"{TP}.members.body.min[2]", 0.05), f"{TP}.members.body.max[2]"
    ),
    case("member-huge", at(f"{TP}.members.body.max[0]", 50.0), f"{TP}.members.body.max[0]"),
    case("member-no-body", at(f"{TP}.members.body.kind", "handle"), f"{TP}.members", "body"),
    case(
        "member-two-bodies",
        at(f"{TP}.members.rim", {"min": [-0.1, -0.1, 0.0], "max": [0.1, 0.1, 0.02]}),
        f"{TP}.members",
        "exactly one",
    ),
    case("member-kind-number", at(f"{TP}.members.body.kind", 1), f"{TP}.members.body.kind"),
    case("member-geom-unknown", at(f"{TP}.members.body.geom", "sphere"), f"{TP}.members.body.geom"),
    case(
        "member-name-invalid",
        lambda d: d["types"]["plate"]["members"].update(
            {"Rim Part": {"kind": "edge", "min": [0, 0, 0], "max": [0.1, 0.1, 0.01]}}
        ),
        f'{TP}.members."Rim Part"',
    ),
    case("member-unknown-key", at(f"{TP}.members.body.radius", 0.1), f"{TP}.members.body.radius"),
    case("parts-missing", drop(f"{TP}.parts"), f"{TP}.parts"),
    case("parts-number", at(f"{TP}.parts", 5), f"{TP}.parts"),
    case("part-number", at(f"{TP}.parts.on", 5), f"{TP}.parts.on"),
    case("part-not-a-side", at(f"{TP}.parts.in", {"shape": "open"}), f"{TP}.parts.in", "on, under"),
    case("part-missing", drop(f"{TP}.parts.left"), f"{TP}.parts", "left"),
    case("part-shape-missing", drop(f"{TP}.parts.on.shape"), f"{TP}.parts.on.shape"),
    case("part-shape-unknown", at(f"{TP}.parts.on.shape", "square"), f"{TP}.parts.on.shape"),
    case("part-height-nan", at(f"{TP}.parts.on.height", NAN), f"{TP}.parts.on.height", "finite"),
    case("part-height-inf", at(f"{TP}.parts.on.height", -INF), f"{TP}.parts.on.height"),
    case("part-height-above-body", at(f"{TP}.parts.on.height", 1.0), f"{TP}.parts.on.height"),
    case("part-size-negative", at(f"{TP}.parts.on.size[0]", -0.18), f"{TP}.parts.on.size[0]"),
    case("part-size-nan", at(f"{TP}.parts.on.size[1]", NAN), f"{TP}.parts.on.size[1]"),
    case("part-size-short", at(f"{TP}.parts.on.size", [0.18]), f"{TP}.parts.on.size"),
    case("part-size-too-big", at(f"{TP}.parts.on.size", [0.5, 0.18]), f"{TP}.parts.on.size"),
    case("part-center-nan", at(f"{TP}.parts.on.center[0]", NAN), f"{TP}.parts.on.center[0]"),
    case("part-center-outside", at(f"{TP}.parts.on.center", [0.3, 0.0]), f"{TP}.parts.on.center"),
    case(
        "part-food-surface-string",
        at(f"{TP}.parts.under.food_surface", "true"),
        f"{TP}.parts.under.food_surface",
        "true or false",
    ),
    case("part-unknown-key", at(f"{TP}.parts.on.colour", "white"), f"{TP}.parts.on.colour"),
]

KT = "types.kitchen-table"
CATALOGUE_CASES = [
    case("catalogue-non-utf8", raw(b"# \xff\xfe\n[types]\n"), None, "UTF-8"),
    case("catalogue-empty", raw(b""), "types"),
    case("catalogue-types-number", at("types", 5), "types"),
    case("catalogue-types-empty", at("types", {}), "types"),
    case("catalogue-unknown-top-key", at("version", 2), "version"),
    case("catalogue-mass-nan", at("types.salt-shaker.mass", NAN), "types.salt-shaker.mass"),
    case("catalogue-movable-string", at(f"{KT}.movable", "false"), f"{KT}.movable"),
    case("catalogue-parts-number", at("types.glass-mug.parts", 5), "types.glass-mug.parts"),
    case(
        "catalogue-member-nan",
        at("types.frying-pan.members.handle.min[2]", NAN),
        "types.frying-pan.members.handle.min[2]",
    ),
    case(
        "catalogue-type-name-invalid",
        lambda d: d["types"].update({"Pan": d["types"]["frying-pan"]}),
        "types.Pan",
    ),
]


def _write(tmp_path: Path, base: dict[str, Any], c: Case) -> Path:
    data = copy.deepcopy(base)
    content = c.edit(data)
    path = tmp_path / f"{c.id}.toml"
    path.write_bytes(content if content is not None else tomli_w.dumps(data).encode())
    return path


def _check(error: SceneError, path: Path, c: Case) -> None:
    message = str(error)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    if c.field is not None:
        assert error.field == c.field
        assert f"{path}: field '{c.field}': " in message
    assert c.words in message


@pytest.mark.parametrize("c", SCENE_CASES, ids=[c.id for c in SCENE_CASES])
def test_malformed_scene_file_is_a_scene_error_naming_the_field(tmp_path: Path, c: Case) -> None:
    path = _write(tmp_path, base_scene(), c)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    _check(info.value, path, c)


@pytest.mark.parametrize("c", CATALOGUE_CASES, ids=[c.id for c in CATALOGUE_CASES])
def test_malformed_catalogue_is_a_scene_error_naming_the_field(tmp_path: Path, c: Case) -> None:
    path = _write(tmp_path, base_catalogue(), c)
    with pytest.raises(SceneError) as info:
        load_catalogue(path)
    _check(info.value, path, c)


def test_base_files_are_valid(tmp_path: Path) -> None:
    """The audit's starting points load, so every failure above is the edit's doing."""
    scene = scene_from_dict(base_scene(), file="base.toml")
    assert scene.stacks["slot1"] == ("tray", "plate")
    assert scene.type_of("plate").parts["on"].height == 0.02
    path = tmp_path / "base.toml"
    path.write_text(scene_to_toml(scene))
    again = load_scene(path)
    assert again.poses == scene.poses
    assert scene_to_dict(again) == scene_to_dict(scene)
    assert again.type_of("plate").extra["rgba"] == (0.9, 0.9, 0.85, 1.0)  # kept by the export
    path.write_text(tomli_w.dumps(base_catalogue()))
    assert load_catalogue(path) == load_catalogue()


@pytest.mark.parametrize(
    "c",
    [
        c
        for c in SCENE_CASES
        if c.id
        in {
            "non-utf8-latin1",
            "slot-name-duplicate",
            "mass-nan",
            "parts-number",
            "objects-empty",
            "movable-string",
        }
    ],
    ids=lambda c: c.id,
)
@pytest.mark.parametrize("command", ["scenes show", "plan", "run"])
def test_cli_exits_two_with_one_line_naming_file_and_field(
    capsys, tmp_path: Path, c: Case, command: str
) -> None:
    path = _write(tmp_path, base_scene(), c)
    assert main([*command.split(), str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"utamp: error: {path}: ")
    if c.field is not None:
        assert f"field '{c.field}'" in lines[0]


def test_scene_without_a_tower_base_names_goal_base(capsys, tmp_path: Path) -> None:
    """A scene with no wooden tray and no `goal_base` loads, but planning names the field."""
    data = base_scene()
    data["objects"][0]["type"] = "cutting-board"
    del data["goal_base"], data["objects"][0]["position"]
    path = tmp_path / "no-tray.toml"
    path.write_text(tomli_w.dumps(data))
    scene = load_scene(path)
    with pytest.raises(SceneError) as info:
        scene.tower_base  # noqa: B018
    assert info.value.field == "goal_base"
    assert main(["plan", str(path)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [f"utamp: error: {info.value}"]
    assert str(info.value).startswith(f"{path}: field 'goal_base': ")


def test_utf8_with_byte_order_mark_loads(tmp_path: Path) -> None:
    """Editors that write a UTF-8 byte-order mark produce a valid file, not an error."""
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + tomli_w.dumps(base_scene()).encode())
    assert load_scene(path).n_objects == 6


@pytest.mark.parametrize("domain", DOMAINS)
def test_reserved_names_cover_the_domain_constants(domain: str) -> None:
    """A slot, space or object named like a PDDL constant would clash in the problem."""
    assert set(parse_domain(domain_text(domain)).constants) <= RESERVED
