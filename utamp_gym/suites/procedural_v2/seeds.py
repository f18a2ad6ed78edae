"""The kept seed lists of procedural-v2's splits with their labels: scenes (with a cache file
per machine, as v1's), names and SHA-256 digests.

The split file (``assets/procedural/procedural-v2.toml``) keeps per split: ``domain`` (the
domain the labels assume), ``labeller`` (the planner method), ``templates`` (the goal ids it
draws from), ``seeds``, and per seed ``achievable`` and ``plan_length`` (0 if unachievable),
``sha256`` / ``sample_sha256`` (`split_digest`)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any, NamedTuple

import tomli

from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import assets_dir
from utamp_gym.scene.model import Scene
from utamp_gym.suites.procedural.objects import _catalogue
from utamp_gym.suites.procedural_v2.scenes import generate_scene
from utamp_gym.suites.procedural_v2.spec import SEEDS_FILE, SPLITS, SUITE, check_split
from utamp_gym.suites.split_cache import read_split, toml_digest, write_split
from utamp_gym.suites.split_cache import split_names as names_of

SAMPLE_STEP = 20  # `sample_sha256` covers scenes 0, 20, 40, ...


class V2Scene(NamedTuple):
    """A kept scene of a split: the scene (with its goal), its seed, families, template and
    the split file's labels."""

    scene: Scene
    seed: int
    families: tuple[str, ...]
    template: str
    achievable: bool
    plan_length: int


@lru_cache(maxsize=1)
def _seed_table() -> dict[str, Any]:
    path = assets_dir().joinpath(*SEEDS_FILE)  # not yet written: no split generated
    return tomli.loads(path.read_text()) if path.is_file() else {}


def _entry(split: str) -> dict[str, Any]:
    table = _seed_table()
    if check_split(split) not in table:
        raise UnknownNameError(f"{SUITE} split (generated)", split, table)
    return table[split]


def split_seeds(split: str) -> tuple[int, ...]:
    return tuple(int(s) for s in _entry(split)["seeds"])


def split_domain(split: str) -> str:
    """The domain the split's achievability labels assume."""
    return str(_entry(split)["domain"])


def split_hash(split: str) -> str:
    return str(_entry(split)["sha256"])


def sample_hash(split: str) -> str:
    return str(_entry(split)["sample_sha256"])


def available_splits() -> tuple[str, ...]:
    """The splits the split file holds (all of `SPLITS` once generated)."""
    return tuple(s for s in SPLITS if s in _seed_table())


def _labelled(split: str, index: int, scene: Any) -> V2Scene:
    e = _entry(split)
    return V2Scene(
        scene.scene, scene.seed, scene.families, scene.template,
        bool(e["achievable"][index]), int(e["plan_length"][index]),
    )  # fmt: skip


@lru_cache(maxsize=4096)
def split_scene(split: str, index: int) -> V2Scene:
    """The `index`-th scene of a split (from the cache file if there is one)."""
    seeds = split_seeds(split)
    if not 0 <= index < len(seeds):
        raise UnknownNameError("scene", f"{SUITE}/{split}/{index:04d}", split_names(split)[:3])
    cached = _read_cache(split)
    if cached is not None:
        return cached[index]
    return _labelled(split, index, generate_scene(split, seeds[index], index))


def split_scenes(split: str) -> tuple[V2Scene, ...]:
    """Every scene of a split, in order (cached per machine like v1's splits:
    ``$XDG_CACHE_HOME/utamp_gym/procedural-v2-<split>-<sha256>.json``)."""
    cached = _read_cache(split)
    if cached is not None:
        return cached
    seeds = split_seeds(split)
    scenes = tuple(_labelled(split, i, generate_scene(split, s, i)) for i, s in enumerate(seeds))
    _write_cache(split, scenes)
    return scenes


@lru_cache(maxsize=len(SPLITS))
def _read_cache(split: str) -> tuple[V2Scene, ...] | None:
    rows = read_split(SUITE, split, split_hash(split), len(split_seeds(split)), _catalogue())
    if rows is None:
        return None
    return tuple(
        V2Scene(
            scene, int(r["seed"]), tuple(r["families"]), str(r["template"]),
            bool(r["achievable"]), int(r["plan_length"]),
        )
        for scene, r in rows
    )  # fmt: skip


def _write_cache(split: str, scenes: tuple[V2Scene, ...]) -> None:
    rows = [
        (g.scene, {**{k: v for k, v in g._asdict().items() if k != "scene"},
                   "families": list(g.families)})
        for g in scenes
    ]  # fmt: skip
    if write_split(SUITE, split, split_hash(split), rows):
        _read_cache.cache_clear()


def split_names(split: str) -> list[str]:
    return names_of(SUITE, split, len(split_seeds(split)))


def split_digest(split: str, step: int = 1, seeds: tuple[int, ...] | None = None) -> str:
    """SHA-256 over the split's scene files (TOML with the goal, in order, each followed by
    a NUL), each generated anew (never from the cache); every `step`-th only if `step` > 1."""
    seeds = split_seeds(split) if seeds is None else seeds
    return toml_digest(generate_scene(split, seeds[i], i).scene for i in range(0, len(seeds), step))


def parse_name(name: str) -> tuple[str, int] | None:
    """``procedural-v2/train/0042`` -> ("train", 42); None if not such a name."""
    suite, _, rest = name.partition("/")
    split, _, number = rest.rpartition("/")
    if suite != SUITE or split not in SPLITS or len(number) != 4 or not number.isdigit():
        return None
    return split, int(number)
