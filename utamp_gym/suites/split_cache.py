"""The per-machine cache of a generated split's scenes (procedural-v1 and procedural-v2).

Why: generating a split takes seconds (some scenes are found by search), so each split's
scenes are kept as JSON records in ``$XDG_CACHE_HOME/utamp_gym/<suite>-<split>-<sha>.json``
(``~/.cache`` without XDG_CACHE_HOME), named by the SHA-256 the repository keeps for the
split: a new seed list or generator comes with a new name. A file is written whole,
atomically; one that cannot be written is simply not kept, and one that cannot be read (or
holds another number of records) is as good as none.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from utamp_gym.scene.catalogue import Catalogue
from utamp_gym.scene.io import scene_from_dict, scene_to_dict, scene_to_toml
from utamp_gym.scene.model import Scene


def cache_path(suite: str, split: str, sha256: str) -> Path:
    """Where the cache of `suite`'s `split`, whose kept hash is `sha256`, lives."""
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "utamp_gym" / f"{suite}-{split}-{sha256[:16]}.json"


def read_records(path: Path, count: int) -> list[dict[str, Any]] | None:
    """The `count` records kept in `path` (None: no such file, unreadable, or another
    count)."""
    try:
        records = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(records, list) or len(records) != count:
        return None
    return records


def write_records(path: Path, records: Sequence[dict[str, Any]]) -> bool:
    """Write `records` to `path` atomically; whether it was kept."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False) as f:
            json.dump(list(records), f)
        os.replace(f.name, path)
    except OSError:
        return False
    return True


def split_names(suite: str, split: str, count: int) -> list[str]:
    """``<suite>/<split>/0000`` ... for a split of `count` scenes."""
    return [f"{suite}/{split}/{i:04d}" for i in range(count)]


def read_split(
    suite: str, split: str, sha256: str, count: int, catalogue: Catalogue
) -> list[tuple[Scene, dict[str, Any]]] | None:
    """The `count` cached scenes of a split (types from `catalogue`), each with its record's
    other fields; None when there is no usable cache."""
    path = cache_path(suite, split, sha256)
    records = read_records(path, count)
    if records is None:
        return None
    file = f"<{suite} {split} cache {path.name}>"
    return [(scene_from_dict(r["scene"], file=file, catalogue=catalogue), r) for r in records]


def write_split(
    suite: str, split: str, sha256: str, rows: Iterable[tuple[Scene, Mapping[str, Any]]]
) -> bool:
    """Cache a split's scenes, each with its other fields (JSON-able); whether it was kept."""
    records = [{**fields, "scene": scene_to_dict(scene)} for scene, fields in rows]
    return write_records(cache_path(suite, split, sha256), records)


def toml_digest(scenes: Iterable[Scene]) -> str:
    """SHA-256 over the scenes' files (TOML, in order, each followed by a NUL)."""
    h = hashlib.sha256()
    for scene in scenes:
        h.update(scene_to_toml(scene).encode())
        h.update(b"\0")
    return h.hexdigest()
