"""benchmarks/attribute_model.py: the ceiling's mass is reckoned as the perceiver reckons it
(`perception.volumes.mass_areas`: a slab weighed solid), and a cache collected before the
rows carried those areas is refused by name rather than read with the shell area."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import attribute_model as am

from utamp_gym.perception.learned import MODEL_FILE
from utamp_gym.perception.material import estimate_mass
from utamp_gym.scene.materials import material

VOLUME = 0.25 * 0.16 * 0.018  # a 25 x 16 x 1.8 cm board
SHELL = 2 * (0.25 * 0.16 + 0.25 * 0.018 + 0.16 * 0.018)


def _row(mass_areas: list[float | None]) -> dict[str, object]:
    return {"object": "board", "measurements": {"volume": VOLUME, "area": SHELL},
            "mass_areas": mass_areas}  # fmt: skip


def test_a_slab_row_is_weighed_by_its_whole_volume_a_walled_one_by_its_walls() -> None:
    plastic = material("plastic")
    assert plastic.wall is not None and SHELL * plastic.wall < VOLUME  # walls weigh less
    solid = am._rule_mass("plastic", _row([None, None]))
    assert am.areas(_row([None, None])) == (float("inf"), float("inf"))
    assert solid == pytest.approx(VOLUME * plastic.density)
    walled = am._rule_mass("plastic", _row([SHELL, SHELL]))
    assert walled == pytest.approx(estimate_mass("plastic", VOLUME, SHELL)[0])
    assert walled < 0.5 * solid


def test_a_cache_without_mass_areas_is_refused_naming_the_file(tmp_path: Path) -> None:
    folder = tmp_path / "procedural-v1_train"
    folder.mkdir()
    old = _row([SHELL, SHELL])
    del old["mass_areas"]
    (folder / "0001.json").write_text(json.dumps([old]))
    with pytest.raises(SystemExit, match=r"0001\.json.*mass_areas"):
        am.cached("procedural-v1/train", tmp_path)
    (folder / "0001.json").write_text(json.dumps([_row([None, None])]))
    assert am.cached("procedural-v1/train", tmp_path)[0]["object"] == "board"


@pytest.mark.slow
def test_the_shipped_model_is_what_train_makes_of_the_current_perceivers_measurements(
    tmp_path: Path,
) -> None:
    """The shipped weights come out of the script (`train --limit 120`) on the measurements
    the perceiver makes now: a perceiver change that moves them asks for a retrain."""
    am.collect(am.TRAIN, tmp_path)
    for suite in am.PAPER:
        am.collect(suite, tmp_path, (1, 10))
    made = am.train(tmp_path, write=False, limit=120)["model"].to_json()
    shipped = json.loads((Path(am.ROOT) / "assets" / Path(*MODEL_FILE)).read_text())
    assert made.keys() == shipped.keys()
    for key, value in shipped.items():
        if isinstance(value, list) and key not in ("materials", "mass_bounds"):
            np.testing.assert_allclose(np.asarray(made[key]), np.asarray(value), atol=1e-5)
        elif isinstance(value, float):
            assert made[key] == pytest.approx(value, rel=1e-6), key
        else:
            assert made[key] == value, key
