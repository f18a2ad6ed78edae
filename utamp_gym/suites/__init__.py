"""Benchmark suites and scene lookup by name or path."""

from __future__ import annotations

from pathlib import Path

from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import assets_dir
from utamp_gym.scene.io import load_scene
from utamp_gym.scene.model import Scene
from utamp_gym.suites.generate import SUITES, all_scene_names, get_scene, suite_scenes, suite_stats


def packaged_scene_names() -> list[str]:
    """Scene files shipped in `assets/scenes/` (by stem), e.g. ``kitchen-demo``."""
    return sorted(p.stem for p in (assets_dir() / "scenes").glob("*.toml") if p.stem != "layout")


def resolve_scene(ref: str) -> Scene:
    """A scene from a suite name (``pick-place/017``), a packaged name or a file path.

    Only the scene asked for is built; the lists of valid names are made for errors only.
    """
    suite = ref.split("/", 1)[0]
    if suite in SUITES and not Path(ref).exists():
        try:
            return get_scene(ref)
        except UnknownNameError:  # list that suite's scenes (the first 40 are shown)
            raise UnknownNameError(
                "scene", ref, [*packaged_scene_names(), *all_scene_names(suite)]
            ) from None
    packaged = assets_dir() / "scenes" / f"{ref}.toml"
    if "/" not in ref and ref != "layout" and packaged.is_file():
        return load_scene(packaged)
    path = Path(ref)
    if path.suffix == ".toml" or path.exists():
        return load_scene(path)
    raise UnknownNameError("scene", ref, _valid_names())


def _valid_names() -> list[str]:
    return [*packaged_scene_names(), *all_scene_names()]


__all__ = [
    "SUITES",
    "all_scene_names",
    "get_scene",
    "packaged_scene_names",
    "resolve_scene",
    "suite_scenes",
    "suite_stats",
]
