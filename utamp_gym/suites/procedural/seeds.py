"""The kept seed lists of the splits: their scenes (with a cache file per machine), names and
SHA-256 digests."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import tomli

from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.suites.procedural.layout import (
    generate_scene,
)
from utamp_gym.suites.procedural.objects import (
    _catalogue,
)
from utamp_gym.suites.procedural.spec import (
    SEEDS_FILE,
    SPECS,
    SPLITS,
    SUITE,
    Generated,
    _check_split,
)
from utamp_gym.suites.split_cache import read_split, toml_digest, write_split
from utamp_gym.suites.split_cache import split_names as names_of


@lru_cache(maxsize=1)
def _seed_table() -> dict[str, Any]:
    return tomli.loads(asset_path(*SEEDS_FILE).read_text())


def split_seeds(split: str) -> tuple[int, ...]:
    """The scene seeds of a split, in scene order."""
    return tuple(int(s) for s in _seed_table()[_check_split(split)]["seeds"])


def split_hash(split: str) -> str:
    """The SHA-256 of the split's scene files kept with its seeds."""
    return str(_seed_table()[_check_split(split)]["sha256"])


@lru_cache(maxsize=4096)
def split_scene(split: str, index: int) -> Generated:
    """The `index`-th scene of a split: from the split's cache file if there is one (see
    `split_scenes`), else generated (only that one)."""
    seeds = split_seeds(split)
    if not 0 <= index < len(seeds):
        raise UnknownNameError("scene", f"{SUITE}/{split}/{index:04d}", split_names(split)[:3])
    cached = _read_cache(split)
    if cached is not None:
        return cached[index]
    return generate_scene(split, seeds[index], index)


def split_scenes(split: str) -> tuple[Generated, ...]:
    """Every scene of a split, in order.

    Generating a split takes seconds (test-count's six-object towers are found by search),
    so the scenes are kept in a cache file per machine, named by the SHA-256 the repository
    keeps for the split: ``$XDG_CACHE_HOME/utamp_gym/procedural-v1-<split>-<sha256>.json``
    (``~/.cache`` without XDG_CACHE_HOME). A new seed list or generator comes with a new
    SHA-256 (`tests/test_procedural.py` regenerates every split, without the cache, and
    compares), hence a new file. The file is written whole, atomically; one that cannot be
    written is simply not kept."""
    cached = _read_cache(split)
    if cached is not None:
        return cached
    scenes = tuple(generate_scene(split, s, i) for i, s in enumerate(split_seeds(split)))
    _write_cache(split, scenes)
    return scenes


@lru_cache(maxsize=len(SPLITS))
def _read_cache(split: str) -> tuple[Generated, ...] | None:
    rows = read_split(SUITE, split, split_hash(split), len(split_seeds(split)), _catalogue())
    if rows is None:
        return None
    return tuple(
        Generated(scene, int(r["seed"]), tuple(r["families"]), bool(r["achievable"]))
        for scene, r in rows
    )


def _write_cache(split: str, scenes: tuple[Generated, ...]) -> None:
    rows = [
        (g.scene, {"seed": g.seed, "families": list(g.families), "achievable": g.achievable})
        for g in scenes
    ]
    if write_split(SUITE, split, split_hash(split), rows):
        _read_cache.cache_clear()


def split_names(split: str) -> list[str]:
    return names_of(SUITE, split, len(split_seeds(split)))


def split_digest(split: str, step: int = 1) -> str:
    """SHA-256 over the split's scene files (TOML, in order, each followed by a NUL), each
    generated anew from its seed (never read from the cache); with `step` > 1 over every
    step-th scene only (the quick check kept as ``sample_sha256``)."""
    seeds = split_seeds(split)
    return toml_digest(generate_scene(split, seeds[i], i).scene for i in range(0, len(seeds), step))


SAMPLE_STEP = 20  # `sample_sha256` covers scenes 0, 20, 40, ...


def sample_hash(split: str) -> str:
    """The SHA-256 of every `SAMPLE_STEP`-th scene file of a split, kept with its seeds."""
    return str(_seed_table()[_check_split(split)]["sample_sha256"])


def parse_name(name: str) -> tuple[str, int] | None:
    """``procedural-v1/train/0042`` -> ("train", 42); None if not such a name."""
    suite, _, rest = name.partition("/")
    split, _, number = rest.rpartition("/")
    if suite != SUITE or split not in SPECS or len(number) != 4 or not number.isdigit():
        return None
    return split, int(number)
