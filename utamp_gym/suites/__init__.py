"""Benchmark suites and scene lookup by name or path.

The enumerated suites (`generate`: pick-place, sliding, extra) and the procedural splits
(`procedural`: ``procedural-v1/train``, ``/test-instances``, ``/test-families``,
``/test-count``) answer to the same functions; the procedural module (and with it numpy and
the kitchenware generator) is imported only when one of its names is used, so that
``utamp plan pick-place/017`` stays light.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
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
PROCEDURAL_V2 = "procedural-v2"
#: the splits of procedural-v2, whose scenes carry their goals (`utamp_gym.suites.procedural_v2`;
#: the envs read them: `utamp_gym.env.goals`)
GOAL_SUITES = tuple(
    f"{PROCEDURAL_V2}/{s}"
    for s in ("train", "test-instances", "test-families", "test-count", "test-tasks", "hard")
)


def _generated(suites: Sequence[str]) -> tuple[str, ...]:
    """The procedural-v2 splits its split file holds (``procedural_v2.available_splits``,
    read here without importing the generator: it imports this module). Only the file's
    top-level table headers are read: parsing all of it cost every ``utamp`` command 3 ms."""
    path = assets_dir() / "procedural" / f"{PROCEDURAL_V2}.toml"
    text = path.read_text() if path.is_file() else ""
    tables = set(re.findall(r"^\[([\w-]+)\][ \t]*$", text, re.MULTILINE))
    return tuple(s for s in suites if s.rpartition("/")[2] in tables)


#: every suite a sweep, an env or ``utamp run`` / ``utamp eval`` accepts: the enumerated
#: suites, the procedural-v1 splits and the procedural-v2 splits generated so far
ALL_SUITES = (*SUITES, *PROCEDURAL_SUITES, *_generated(GOAL_SUITES))
#: what ``utamp scenes list`` lists
LISTED_SUITES = (*ALL_SUITES, *(s for s in GOAL_SUITES if s not in ALL_SUITES))


def _split(suite: str) -> str:
    return suite.removeprefix(f"{PROCEDURAL}/")


class UnknownSceneError(UnknownNameError):
    """A scene name that is none of the valid ones: one line that suggests the nearest names
    (`nearest_scene_names`) and, for a suite's numbered name, that suite's range."""

    def __init__(self, name: str, valid: Sequence[str] | None = None):
        names = list(valid) if valid is not None else _valid_names()
        super().__init__("scene", name, names)
        self.suggestions = nearest_scene_names(name, names)
        near, message = self.suggestions, f"unknown scene '{name}'"
        if not near:
            message += f"; valid: {', '.join(_ranges(names))} or a scene file (.toml)"
        else:
            message += f"; did you mean {', '.join(near[:-1]) + ' or ' if near[1:] else ''}"
            message += f"{near[-1]}?"
            suite = name.strip().rpartition("/")[0]
            own = [n for n in names if suite and n.rpartition("/")[0] == suite]
            if own and near != [_normalised(name, set(names))]:  # e.g. a number out of range
                message += f" ({suite} has {_ranges(own)[0]})"
        self.args = (message,)


def nearest_scene_names(name: str, valid: Sequence[str], n: int = 3) -> list[str]:
    """The valid names nearest to `name`: its number zero-padded to a suite's width
    (``pick-place/17`` -> ``pick-place/017``) if that is one, else up to `n` close matches
    (`difflib`, most similar first)."""
    normalised = _normalised(name, set(valid))
    if normalised is not None:
        return [normalised]
    import difflib  # stdlib, only for a name that is not a scene: off `utamp plan`'s start-up

    return difflib.get_close_matches(name, list(valid), n=n, cutoff=0.6)


def _normalised(name: str, known: set[str]) -> str | None:
    """`name` stripped, in lower case and with its number zero-padded (3 or 4 digits), if
    that is a known name."""
    name = name.strip().lower()
    prefix, _, number = name.rpartition("/")
    candidates = [name]
    if prefix and number.isdigit():
        candidates += [f"{prefix}/{int(number):0{width}d}" for width in (3, 4)]
    return next((c for c in candidates if c in known), None)


def _ranges(names: Sequence[str]) -> list[str]:
    """Names with the numbered ones of each prefix folded: ``pick-place/000 to 105``."""
    single: list[str] = []
    numbered: dict[str, list[str]] = {}
    for n in names:
        prefix, _, number = n.rpartition("/")
        if prefix and number.isdigit():
            numbered.setdefault(prefix, []).append(n)
        else:
            single.append(n)
    return single + [
        v[0] if len(v) == 1 else f"{v[0]} to {v[-1].rpartition('/')[2]}" for v in numbered.values()
    ]


def _check_suite(suite: str) -> None:
    if suite not in LISTED_SUITES:
        raise UnknownNameError("suite", suite, LISTED_SUITES)


def _v2_split(suite: str) -> str | None:
    """The procedural-v2 split a suite name is (None if another suite)."""
    if suite not in GOAL_SUITES:
        return None
    return suite.removeprefix(f"{PROCEDURAL_V2}/")


def suite_scenes(suite: str) -> tuple[Scene, ...]:
    """All scenes of a suite, in their stable order."""
    _check_suite(suite)
    if suite in PROCEDURAL_SUITES:
        # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural
        from utamp_gym.suites import procedural

        return tuple(g.scene for g in procedural.split_scenes(_split(suite)))
    if (split := _v2_split(suite)) is not None:
        # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural_v2
        from utamp_gym.suites import procedural_v2

        return tuple(g.scene for g in procedural_v2.split_scenes(split))
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
            # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural
            from utamp_gym.suites import procedural

            out += procedural.split_names(_split(name))
        elif (split := _v2_split(name)) is not None:
            # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural_v2
            from utamp_gym.suites import procedural_v2

            out += procedural_v2.split_names(split)
        else:
            out += _enumerated.all_scene_names(name)
    return out


def get_scene(name: str) -> Scene:
    """A suite scene by its stable name (``pick-place/017``, ``procedural-v1/train/0042``)."""
    if name.startswith(f"{PROCEDURAL}/"):
        # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural
        from utamp_gym.suites import procedural

        parsed = procedural.parse_name(name)
        if parsed is not None and parsed[1] < len(procedural.split_seeds(parsed[0])):
            return procedural.split_scene(*parsed).scene
        raise UnknownSceneError(name)
    if name.startswith(f"{PROCEDURAL_V2}/"):
        # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural_v2
        from utamp_gym.suites import procedural_v2

        parsed = procedural_v2.parse_name(name)
        if (
            parsed is not None
            and parsed[0] in procedural_v2.available_splits()
            and parsed[1] < len(procedural_v2.split_seeds(parsed[0]))
        ):
            return procedural_v2.split_scene(*parsed).scene
        raise UnknownSceneError(name, _v2_names())
    try:
        return _get_enumerated(name)
    except UnknownNameError:
        raise UnknownSceneError(name) from None


def scene_summary(suite: str) -> list[dict[str, Any]]:
    """One record per scene of a suite: ``name``, ``n_objects``, ``families`` (the kitchenware
    family of each object, the base first; for the enumerated suites the object types),
    ``template`` and ``instruction`` of its goal (the suites before procedural-v2: the
    paper's tower) and ``achievable`` (the rules' verdict on the goal; the enumerated suites
    keep only achievable scenes; procedural-v2: the planner's label)."""
    # lazy: keeps `utamp plan` from loading utamp_gym.tasks.language and .templates
    from utamp_gym.tasks.language import instruction
    from utamp_gym.tasks.templates import tower_goal  # lazy: as above

    _check_suite(suite)

    def record(scene: Scene, families: Sequence[str], achievable: bool) -> dict[str, Any]:
        goal = scene.goal if scene.goal is not None else tower_goal(scene)
        return {
            "name": scene.name,
            "n_objects": scene.n_objects,
            "families": list(families),
            "template": goal.template,
            "instruction": instruction(scene, goal),
            "achievable": achievable,
        }

    if suite in PROCEDURAL_SUITES:
        # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural
        from utamp_gym.suites import procedural

        return [record(g.scene, g.families, g.achievable)
                for g in procedural.split_scenes(_split(suite))]  # fmt: skip
    if (split := _v2_split(suite)) is not None:
        # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural_v2
        from utamp_gym.suites import procedural_v2

        return [record(g.scene, g.families, g.achievable)
                for g in procedural_v2.split_scenes(split)]  # fmt: skip
    return [record(s, [o.type for o in s.objects], True) for s in _enumerated.suite_scenes(suite)]


def packaged_scene_names() -> list[str]:
    """Scene files shipped in `assets/scenes/` (by stem), e.g. ``kitchen-demo``."""
    return sorted(p.stem for p in (assets_dir() / "scenes").glob("*.toml") if p.stem != "layout")


def resolve_scene(ref: str) -> Scene:
    """A scene from a suite name (``pick-place/017``, ``procedural-v1/train/0042``), a
    packaged name or a file path.

    Only the scene asked for is built; the lists of valid names are made for errors only.
    """
    suite = ref.split("/", 1)[0]
    if suite in (PROCEDURAL, PROCEDURAL_V2, *_enumerated.SUITES) and not Path(ref).exists():
        return get_scene(ref)  # its error suggests the nearest names (`UnknownSceneError`)
    packaged = assets_dir() / "scenes" / f"{ref}.toml"
    if "/" not in ref and ref != "layout" and packaged.is_file():
        return load_scene(packaged)
    path = Path(ref)
    if path.suffix == ".toml" or path.exists():
        return load_scene(path)
    raise UnknownSceneError(ref)


def suite_of(ref: str) -> str:
    """The suite a suite scene's name belongs to (``procedural-v1/train/0042`` ->
    ``procedural-v1/train``), else ``""``."""
    for s in LISTED_SUITES:
        if ref.startswith(f"{s}/"):
            return s
    return ""


def _v2_names() -> list[str]:
    """The names of the procedural-v2 scenes generated so far."""
    # lazy: keeps `utamp --help` from loading utamp_gym.suites.procedural_v2
    from utamp_gym.suites import procedural_v2

    return [
        n for split in procedural_v2.available_splits() for n in procedural_v2.split_names(split)
    ]


def _valid_names() -> list[str]:
    """Every scene name: the packaged ones, then every suite's (for errors only)."""
    return [*packaged_scene_names(), *all_scene_names()]


__all__ = [
    "ALL_SUITES",
    "GOAL_SUITES",
    "LISTED_SUITES",
    "PROCEDURAL_SUITES",
    "SUITES",
    "UnknownSceneError",
    "all_scene_names",
    "get_scene",
    "nearest_scene_names",
    "packaged_scene_names",
    "resolve_scene",
    "scene_summary",
    "suite_of",
    "suite_scenes",
    "suite_stats",
    "universe_scenes",
]
