"""Scene files: loading, derived poses, round trips and clear errors."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import pytest

from utamp_gym.errors import SceneError, UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene import (
    load_catalogue,
    load_scene,
    scene_from_dict,
    scene_to_dict,
    scene_to_toml,
)


def test_demo_scene_loads_with_stacks_and_poses() -> None:
    scene = load_scene(asset_path("scenes", "kitchen-demo.toml"))
    assert scene.n_objects == 5
    assert scene.stacks["slot1"] == ("tray",)
    assert scene.tower_base == "tray"
    mug = scene.poses["mug"]
    assert mug.quat == (0.0, 1.0, 0.0, 0.0)  # inverted: half turn about x
    assert mug.position[2] == pytest.approx(0.10)  # origin is the (upturned) bottom, 10 cm up
    box = scene.world_box("mug")
    assert box.min[2] == pytest.approx(0.0) and box.max[2] == pytest.approx(0.10)


def test_scene_is_an_immutable_value() -> None:
    scene = load_scene(asset_path("scenes", "kitchen-demo.toml"))
    for again in (pickle.loads(pickle.dumps(scene)), copy.deepcopy(scene)):
        assert again == scene and again is not scene
        assert again.poses == scene.poses and again.catalogue == scene.catalogue
    twin = scene._replace(name="twin")
    assert twin != scene and twin.name == "twin" and scene.name == "kitchen-demo"
    assert twin.objects == scene.objects and twin._replace(name=scene.name) == scene
    with pytest.raises(AttributeError, match="immutable"):
        scene.name = "other"  # type: ignore[misc]
    with pytest.raises(AttributeError, match="immutable"):
        scene.catalogue.types = {}  # type: ignore[misc]
    with pytest.raises(AttributeError):
        scene.objects[0].on = "slot2"  # type: ignore[misc]
    with pytest.raises(TypeError):
        scene._replace(nmae="typo")
    with pytest.raises(TypeError):
        hash(scene)  # its catalogue holds mappings


def test_stacked_object_stands_on_its_support(demo_dict) -> None:
    demo_dict["objects"][4]["on"] = "mug"  # salt onto the inverted mug
    scene = scene_from_dict(demo_dict)
    assert scene.stacks["slot4"] == ("mug", "salt")
    assert scene.poses["salt"].position[2] == pytest.approx(0.10)
    assert scene.poses["salt"].position[:2] == scene.poses["mug"].position[:2]


def test_round_trip_through_toml(tmp_path: Path) -> None:
    scene = load_scene(asset_path("scenes", "kitchen-demo.toml"))
    path = tmp_path / "copy.toml"
    path.write_text(scene_to_toml(scene))
    again = load_scene(path)
    assert scene_to_dict(again) == scene_to_dict(scene)
    assert again.poses == scene.poses


@pytest.mark.parametrize(
    ("mutate", "field", "words"),
    [
        (lambda d: d["objects"][1].update(type="wok"), "objects[1].type", "valid: cutting-board"),
        (lambda d: d["objects"][1].update(on="shelf"), "objects[1].on", "valid:"),
        (lambda d: d["objects"][2].update(on="slot2"), "objects[2].on", "already supports"),
        (
            lambda d: d["objects"][3].update(orientation="sideways"),
            "objects[3].orientation",
            "upright",
        ),
        (lambda d: d["objects"][0].update(name="Tray"), "objects[0].name", "not a valid name"),
        (lambda d: d["objects"][0].update(name="hand"), "objects[0].name", "reserved"),
        (lambda d: d["workspace"].update(min=[0, 0]), "workspace.min", "3 numbers"),
        (lambda d: d["slots"][1].update(position=[5.0, 5.0]), "slots[1].position", "outside"),
        (lambda d: d.update(colour="red"), "colour", "unknown field"),
        (lambda d: d.pop("name"), "name", "missing required field"),
        (lambda d: d.update(name=""), "name", "non-empty"),
        (lambda d: d.update(goal_base="fridge"), "goal_base", "valid: tray"),
    ],
)
def test_malformed_scene_names_file_and_field(
    demo_dict, tmp_path: Path, mutate, field, words
) -> None:
    data = copy.deepcopy(demo_dict)
    mutate(data)
    import tomli_w

    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(data))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert str(path) in message
    assert f"field '{field}'" in message
    assert words in message
    assert info.value.field == field


def test_support_cycle_is_rejected(demo_dict) -> None:
    demo_dict["objects"][3]["on"] = "salt"
    demo_dict["objects"][4]["on"] = "mug"
    with pytest.raises(SceneError, match="cycle"):
        scene_from_dict(demo_dict, file="cyc.toml")


def test_invalid_toml_and_missing_file(tmp_path: Path) -> None:
    bad = tmp_path / "broken.toml"
    bad.write_text("name = [unclosed")
    with pytest.raises(SceneError, match=r"broken\.toml: invalid TOML"):
        load_scene(bad)
    with pytest.raises(SceneError, match="cannot read"):
        load_scene(tmp_path / "missing.toml")


def test_custom_type_in_scene_file(demo_dict) -> None:
    demo_dict["types"] = {
        "plate": {
            "mass": 0.4,
            "material": "ceramic",
            "robustness": "fragile",
            "members": {
                "body": {
                    "kind": "body",
                    "geom": "cylinder",
                    "min": [-0.1, -0.1, 0],
                    "max": [0.1, 0.1, 0.02],
                }
            },
            "parts": {
                p: {"shape": "flat" if p in ("on", "under") else "thin"}
                for p in ("on", "under", "left", "right", "front", "back")
            },
        }
    }
    demo_dict["objects"].append({"name": "plate", "type": "plate", "on": "tray"})
    scene = scene_from_dict(demo_dict)
    assert scene.type_of("plate").mass == 0.4
    assert scene.stacks["slot1"] == ("tray", "plate")
    again = scene_from_dict(scene_to_dict(scene))
    assert again.type_of("plate") == scene.type_of("plate")


def test_custom_type_errors_name_the_field(demo_dict) -> None:
    demo_dict["types"] = {
        "plate": {
            "mass": -1,
            "material": "x",
            "robustness": "fragile",
            "members": {"body": {"min": [0, 0, 0], "max": [1, 1, 1]}},
            "parts": {
                p: {"shape": "flat"} for p in ("on", "under", "left", "right", "front", "back")
            },
        }
    }
    with pytest.raises(SceneError, match=r"field 'types.plate.mass': must be > 0"):
        scene_from_dict(demo_dict, file="custom.toml")


def test_unknown_object_lists_valid_names() -> None:
    scene = load_scene(asset_path("scenes", "kitchen-demo.toml"))
    with pytest.raises(UnknownNameError) as info:
        scene.object("spoon")
    assert "valid: board, mug, pan, salt, tray" in str(info.value)
    with pytest.raises(UnknownNameError, match="valid: cutting-board"):
        load_catalogue()["spoon"]
