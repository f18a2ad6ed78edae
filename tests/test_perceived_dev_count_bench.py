"""benchmarks/perceived_dev_count.py: the six-object development scenes are drawn with
test-count's recipe from seeds no split keeps, so no test scene is read in development."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

from utamp_gym.suites.procedural.seeds import split_scenes, split_seeds  # noqa: E402
from utamp_gym.suites.procedural.spec import SPECS, SPLITS  # noqa: E402

dev = readme.load_script("benchmarks/perceived_dev_count.py")


def test_the_development_seeds_are_no_splits() -> None:
    assert all(max(split_seeds(s)) < dev.FIRST_SEED for s in SPLITS)


def test_a_development_scene_is_six_training_objects_and_no_test_count_scene() -> None:
    rows = []
    for seed in range(dev.FIRST_SEED, dev.FIRST_SEED + 200):  # the first two with a layout
        try:
            rows.append(dev.generate_scene(dev.RECIPE, seed))
        except dev.NoLayout:
            continue
        if len(rows) == 2:
            break
    test_count = {g.scene.objects for g in split_scenes("test-count")}
    train = {*SPECS["train"].families, *SPECS["train"].bases}
    for g in rows:
        assert g.scene.n_objects == 6 and set(g.families) <= train
        assert g.scene.objects not in test_count
