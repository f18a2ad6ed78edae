"""Grounded action universes kept on disk, so a new process does not ground them again.

Why: grounding a suite's universe takes seconds (the procedural splits' geometric universe
most of a training run's start-up), and every `utamp train`, evaluation worker and test
process grounds the same few. A universe is a pure function of its `UniverseKey` and of this
package (code, PDDL domains, scenes), so it is kept under a name made of both: the SHA-256 of
the key and of every file of the package and its assets
(``$XDG_CACHE_HOME/utamp_gym/universe-<key>-<package>.npz``, ``~/.cache`` without
XDG_CACHE_HOME). Any change to the package names new files (the `KEPT` newest per key stay);
a key that names scene files outside the package is never stored (their content is not part
of the name). The file holds arrays and JSON
only (no pickle), is written whole and atomically, and one that cannot be read or written is
simply ignored. ``UTAMP_UNIVERSE_CACHE=0`` turns the store off.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.resources import assets_dir

_PACKAGE = Path(__file__).resolve().parent.parent
#: bump when the stored layout changes
LAYOUT = 1
#: files kept per key (one per package version: a code change names a new file)
KEPT = 4


@lru_cache(maxsize=1)
def package_digest() -> str:
    """SHA-256 over the package's files and its assets (paths and contents)."""
    h = hashlib.sha256()
    for root in (_PACKAGE, assets_dir()):
        for path in sorted(p for p in root.rglob("*") if p.is_file()):
            if "__pycache__" in path.parts or path.suffix == ".pyc":
                continue
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def path_of(key: Any) -> Path | None:
    """Where the universe of `key` is kept (None: the store is off, or the key names scene
    files whose content the name would not cover)."""
    if os.environ.get("UTAMP_UNIVERSE_CACHE", "1") == "0" or key.scenes:
        return None
    of_key = hashlib.sha256(f"{LAYOUT}|{key!r}".encode()).hexdigest()[:16]
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "utamp_gym" / f"universe-{of_key}-{package_digest()[:16]}.npz"


def load(key: Any) -> tuple[dict[str, Any], dict[str, np.ndarray]] | None:
    """(JSON fields, arrays) stored for `key`, or None."""
    path = path_of(key)
    if path is None:
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        fields = json.loads(arrays.pop("_json").tobytes().decode())
    except (OSError, ValueError, KeyError):
        return None
    if fields.get("key") != repr(key):
        return None
    return fields, arrays


def save(key: Any, fields: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    """Store `fields` (JSON) and `arrays` for `key`; a failure leaves nothing behind."""
    path = path_of(key)
    if path is None:
        return
    text = json.dumps({**fields, "key": repr(key)}).encode()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".universe-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez(f, _json=np.frombuffer(text, np.uint8), **arrays)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        _prune(path)
    except OSError:
        pass


def _prune(path: Path) -> None:
    """Keep the `KEPT` newest files of `path`'s key (other versions of the package)."""
    prefix = path.name.rsplit("-", 1)[0]
    files = sorted(path.parent.glob(f"{prefix}-*.npz"), key=lambda p: p.stat().st_mtime)
    for old in files[:-KEPT]:
        old.unlink(missing_ok=True)
