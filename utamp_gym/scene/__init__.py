"""Scene layer: object catalogue, scene model and scene files."""

from utamp_gym.scene.catalogue import Catalogue, ObjectType, load_catalogue
from utamp_gym.scene.io import load_scene, scene_from_dict, scene_to_dict, scene_to_toml
from utamp_gym.scene.model import Pose, Scene, SceneObject, Slot, Space

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
