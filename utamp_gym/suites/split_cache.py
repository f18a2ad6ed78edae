"""The per-machine cache of a generated split's scenes (procedural-v1 and procedural-v2).

Why: generating a split takes seconds (some scenes are found by search), so each split's
scenes are kept as JSON records in ``$XDG_CACHE_HOME/utamp_gym/<suite>-<split>-<sha>.json``
(``~/.cache`` without XDG_CACHE_HOME), named by the SHA-256 the repository keeps for the
split: a new seed list or generator comes with a new name. A file is written whole,
atomically; one that cannot be written is simply not kept, and one that cannot be read (or
holds another number of records) is as good as none.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any


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
