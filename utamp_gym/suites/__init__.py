"""Benchmark suites and scene lookup by name or path.

The enumerated suites (`generate`: pick-place, sliding, extra) and the procedural splits
(`procedural`: ``procedural-v1/train``, ``/test-instances``, ``/test-families``,
``/test-count``) answer to the same functions; the procedural module (and with it numpy and
the kitchenware generator) is imported only when one of its names is used, so that
``utamp plan pick-place/017`` stays light.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import assets_dir
from utamp_gym.scene.io import load_scene
from utamp_gym.scene.model import Scene
from utamp_gym.suites import generate as _enumerated
from utamp_gym.suites.generate import get_scene as _get_enumerated
from utamp_gym.suites.generate import suite_stats

PROCEDURAL = "procedural-v1"
#: the procedural splits, each a suite of its own (`utamp_gym.suites.procedural`)
PROCEDURAL_SUITES = tuple(
    f"{PROCEDURAL}/{s}" for s in ("train", "test-instances", "test-families", "test-count")
)
#: the enumerated suites (`suite_stats` describes them)
SUITES = _enumerated.SUITES
#: every suite a sweep, an env or ``utamp scenes list`` accepts: the enumerated and the splits
ALL_SUITES = (*SUITES, *PROCEDURAL_SUITES)


def _split(suite: str) -> str:
    return suite.removeprefix(f"{PROCEDURAL}/")


def _check_suite(suite: str) -> None:
    if suite not in ALL_SUITES:
        raise UnknownNameError("suite", suite, ALL_SUITES)


def suite_scenes(suite: str) -> tuple[Scene, ...]:
    """All scenes of a suite, in their stable order."""
    _check_suite(suite)
    if suite in PROCEDURAL_SUITES:
        from utamp_gym.suites import procedural

        return tuple(g.scene for g in procedural.split_scenes(_split(suite)))
    return _enumerated.suite_scenes(suite)


def universe_scenes(suite: str) -> tuple[Scene, ...]:
    """The scenes an env's action universe is grounded over: a suite's, or for
    ``procedural-v1`` those of all its splits."""
    if suite == PROCEDURAL:
        return tuple(s for split in PROCEDURAL_SUITES for s in suite_scenes(split))
    return suite_scenes(suite)


def all_scene_names(suite: str | None = None) -> list[str]:
    """Names of the scenes of one suite (default: all suites), without building them."""
    suites = ALL_SUITES if suite is None else (suite,)
    for name in suites:
        _check_suite(name)
    out: list[str] = []
    for name in suites:
        if name in PROCEDURAL_SUITES:
            from utamp_gym.suites import procedural

            out += procedural.split_names(_split(name))
        else:
            out += _enumerated.all_scene_names(name)
    return out


def get_scene(name: str) -> Scene:
    """A suite scene by its stable name (``pick-place/017``, ``procedural-v1/train/0042``)."""
    if name.startswith(f"{PROCEDURAL}/"):
        from utamp_gym.suites import procedural

        parsed = procedural.parse_name(name)
        if parsed is not None and parsed[1] < len(procedural.split_seeds(parsed[0])):
            return procedural.split_scene(*parsed).scene
        suite = suite_of(name)
        valid = all_scene_names(suite) if suite else list(PROCEDURAL_SUITES)
        raise UnknownNameError("scene", name, valid)
    return _get_enumerated(name)


def scene_summary(suite: str) -> list[dict[str, Any]]:
    """One record per scene of a suite: ``name``, ``n_objects``, ``families`` (the kitchenware
    family of each object, the base first; for the enumerated suites the object types) and
    ``achievable`` (the rules' verdict on the goal; the enumerated suites keep only
    achievable scenes)."""
    _check_suite(suite)
    if suite in PROCEDURAL_SUITES:
        from utamp_gym.suites import procedural

        out = []
        for g in procedural.split_scenes(_split(suite)):
            out.append(
                {
                    "name": g.scene.name,
                    "n_objects": g.scene.n_objects,
                    "families": list(g.families),
                    "achievable": g.achievable,
                }
            )
        return out
    return [
        {
            "name": s.name,
            "n_objects": s.n_objects,
            "families": [o.type for o in s.objects],
            "achievable": True,
        }
        for s in _enumerated.suite_scenes(suite)
    ]


def packaged_scene_names() -> list[str]:
    """Scene files shipped in `assets/scenes/` (by stem), e.g. ``kitchen-demo``."""
    return sorted(p.stem for p in (assets_dir() / "scenes").glob("*.toml") if p.stem != "layout")


def resolve_scene(ref: str) -> Scene:
    """A scene from a suite name (``pick-place/017``, ``procedural-v1/train/0042``), a
    packaged name or a file path.

    Only the scene asked for is built; the lists of valid names are made for errors only.
    """
    suite = ref.split("/", 1)[0]
    if suite == PROCEDURAL and not Path(ref).exists():
        return get_scene(ref)  # its error lists the split's scenes
    if suite in _enumerated.SUITES and not Path(ref).exists():
        try:
            return get_scene(ref)
        except UnknownNameError:  # list that suite's scenes (the first 40 are shown)
            raise UnknownNameError(
                "scene", ref, [*packaged_scene_names(), *_enumerated.all_scene_names(suite)]
            ) from None
    packaged = assets_dir() / "scenes" / f"{ref}.toml"
    if "/" not in ref and ref != "layout" and packaged.is_file():
        return load_scene(packaged)
    path = Path(ref)
    if path.suffix == ".toml" or path.exists():
        return load_scene(path)
    raise UnknownNameError("scene", ref, _valid_names())


def suite_of(ref: str) -> str:
    """The suite a suite scene's name belongs to (``procedural-v1/train/0042`` ->
    ``procedural-v1/train``), else ``""``."""
    for s in ALL_SUITES:
        if ref.startswith(f"{s}/"):
            return s
    return ""


def _valid_names() -> list[str]:
    return [*packaged_scene_names(), *_enumerated.all_scene_names()]


__all__ = [
    "ALL_SUITES",
    "PROCEDURAL_SUITES",
    "SUITES",
    "all_scene_names",
    "get_scene",
    "packaged_scene_names",
    "resolve_scene",
    "scene_summary",
    "suite_of",
    "suite_scenes",
    "suite_stats",
    "universe_scenes",
]
