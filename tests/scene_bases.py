"""Valid scene and catalogue files (as plain data) that the scene-file tests corrupt.

`base_scene` touches every field of the scene-file schema: the demo scene plus a space in
slot1, a custom `plate` type (with every optional type and part attribute) standing on the
tray, a tray placed by `position` and an explicit `goal_base`.
"""

from __future__ import annotations

import tomllib
from typing import Any

from utamp_gym.resources import asset_path

SIDES = ("on", "under", "left", "right", "front", "back")


def plate_type() -> dict[str, Any]:
    parts: dict[str, Any] = {s: {"shape": "thin"} for s in SIDES}
    parts["on"] = {"shape": "flat", "size": [0.18, 0.18], "center": [0.0, 0.0], "height": 0.02}
    parts["under"] = {"shape": "flat", "food_surface": False}
    return {
        "description": "a flat plate",
        "mass": 0.4,
        "material": "ceramic",
        "robustness": "fragile",
        "movable": True,
        "rgba": [0.9, 0.9, 0.85, 1.0],
        "members": {
            "body": {
                "kind": "body",
                "geom": "cylinder",
                "min": [-0.1, -0.1, 0.0],
                "max": [0.1, 0.1, 0.02],
            }
        },
        "parts": parts,
    }


def base_scene() -> dict[str, Any]:
    """The demo scene, a space in slot1 and a custom `plate` (objects[5]) on the tray."""
    data = tomllib.loads(asset_path("scenes", "kitchen-demo.toml").read_text(encoding="utf-8"))
    data["goal_base"] = "tray"
    data["spaces"] = [
        {"name": "space1", "slot": "slot1", "position": [0.5, 0.0], "size": [0.45, 0.32]}
    ]
    data["types"] = {"plate": plate_type()}
    data["objects"][0]["position"] = [0.5, 0.0]
    data["objects"].append({"name": "plate", "type": "plate", "on": "tray"})
    return data


def base_catalogue() -> dict[str, Any]:
    """The packaged kitchen catalogue."""
    return tomllib.loads(asset_path("objects", "kitchen.toml").read_text(encoding="utf-8"))
