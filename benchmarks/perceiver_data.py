"""What benchmarks/attribute_model.py and perceiver_train.py share: the per-scene rows of the
perceiver cached as JSON (each scene rendered once), and the reliability table of a
confidence (its bins, the share right in each, the expected calibration error)."""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.backend import DEFAULT_BACKEND, backend_factory
from utamp_gym.suites import suite_scenes

#: bins of confidence of the reliability tables
BINS = (0.0, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99, 1.0001)

Row = dict[str, object]


def cached_rows(
    suite: str,
    folder: Path,
    scene_rows: Callable[[Any, Any], list[Row]],
    *,
    part: tuple[int, int] = (1, 1),
    limit: int | None = None,
    file_name: Callable[[str], str] = lambda name: name.rsplit("/", 1)[-1],
) -> list[Row]:
    """`scene_rows(scene, backend)` of every scene of `suite` (its first `limit`; every
    `part[1]`-th from the `part[0]`-th), computed once and read from `folder` after (one
    JSON file per scene, named by `file_name(scene name)`); one backend is built if any
    scene is missing."""
    folder.mkdir(parents=True, exist_ok=True)
    i, n = part
    sim = None
    out: list[Row] = []
    try:
        for k, scene in enumerate(suite_scenes(suite)[:limit]):
            if k % n != i - 1:
                continue
            path = folder / (file_name(scene.name) + ".json")
            if not path.exists():
                sim = sim or backend_factory(DEFAULT_BACKEND)()
                path.write_text(json.dumps(scene_rows(scene, sim)))
            out += json.loads(path.read_text())
    finally:
        if sim is not None:
            sim.close()
    return out


def reliability_table(conf: Sequence[float], right: Sequence[bool]) -> list[dict[str, Any]]:
    """Per bin of `BINS`: objects, mean confidence, share right; then ``{"ece": ...}``, the
    expected calibration error."""
    c, ok = np.asarray(conf, dtype=float), np.asarray(right, dtype=float)
    table: list[dict[str, Any]] = []
    for lo, hi in itertools.pairwise(BINS):
        sel = (c >= lo) & (c < hi)
        if sel.any():
            table.append({"bin": [lo, min(hi, 1.0)], "n": int(sel.sum()),
                          "confidence": float(c[sel].mean()),
                          "accuracy": float(ok[sel].mean())})  # fmt: skip
    ece = sum(t["n"] * abs(t["confidence"] - t["accuracy"]) for t in table) / max(len(ok), 1)
    return [*table, {"ece": float(ece)}]
