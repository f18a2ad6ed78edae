"""Scene layer: object catalogue, scene model and scene files.

The scene-file functions (`load_scene`, `scene_from_dict`, `scene_to_dict`, `scene_to_toml`)
are loaded on first use: `utamp_gym.scene.io` reads a scene's goal through `utamp_gym.tasks`,
whose templates import the scene model (`utamp_gym.scene.model`): scene -> scene.io ->
tasks.templates -> tasks.attributes -> scene (scene.io imports the templates when it reads a
goal given by template).
"""

from typing import Any

from utamp_gym.scene.catalogue import Catalogue, ObjectType, load_catalogue
from utamp_gym.scene.model import Pose, Scene, SceneObject, Slot, Space

_IO = ("load_scene", "scene_from_dict", "scene_to_dict", "scene_to_toml")


def __getattr__(name: str) -> Any:
    if name in _IO:
        # lazy: cycle scene -> scene.io -> tasks.templates -> tasks.attributes -> scene
        from utamp_gym.scene import io

        return getattr(io, name)
    raise AttributeError(f"module 'utamp_gym.scene' has no attribute {name!r}")


__all__ = [
    "Catalogue",
    "ObjectType",
    "Pose",
    "Scene",
    "SceneObject",
    "Slot",
    "Space",
    "load_catalogue",
    "load_scene",
    "scene_from_dict",
    "scene_to_dict",
    "scene_to_toml",
]
