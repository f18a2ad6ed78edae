"""benchmarks/perceiver_data.py: the reliability table and the per-scene row cache that
attribute_model.py and perceiver_train.py share."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from perceiver_data import BINS, cached_rows, reliability_table


def test_reliability_table_bins_and_ece() -> None:
    conf = [0.55, 0.6, 0.97, 0.98, 1.0]
    right = [True, False, True, True, True]
    table = reliability_table(conf, right)
    bins = [t for t in table if "bin" in t]
    assert [t["bin"] for t in bins] == [[0.5, 0.7], [0.95, 0.99], [0.99, 1.0]]
    assert [t["n"] for t in bins] == [2, 2, 1]
    assert bins[0]["accuracy"] == pytest.approx(0.5)
    assert bins[0]["confidence"] == pytest.approx(0.575)
    ece = (2 * abs(0.575 - 0.5) + 2 * abs(0.975 - 1.0) + 1 * abs(1.0 - 1.0)) / 5
    assert table[-1] == {"ece": pytest.approx(ece)}
    assert BINS[-1] > 1.0  # a confidence of exactly 1 falls in the last bin


def test_cached_rows_reads_the_cache_without_rendering(tmp_path: Path) -> None:
    """Scenes already in the folder are read, not rendered: `scene_rows` is not called
    (no backend is built) and `part` / `limit` pick the scenes."""
    names = ["0000", "0001", "0002"]
    for n in names:
        (tmp_path / f"{n}.json").write_text(json.dumps([{"scene": n}]))

    def never(scene, sim):  # type: ignore[no-untyped-def]
        raise AssertionError("a cached scene was rendered again")

    rows = cached_rows("procedural-v1/train", tmp_path, never, limit=3)
    assert [r["scene"] for r in rows] == names
    rows = cached_rows("procedural-v1/train", tmp_path, never, limit=3, part=(2, 2))
    assert [r["scene"] for r in rows] == ["0001"]
