"""benchmarks/attribute_fit.py (attribute_model.py's fitting): leave-one-family-out folds,
and the choice of the material experts' pooling on held-out objects (a head that learns the
family does not carry over to a new one)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import attribute_fit as af
from measurements import cylinder_measurements

from utamp_gym.perception.learned import MATERIAL_NAMES
from utamp_gym.perception.material import FEATURES
from utamp_gym.suites import suite_scenes
from utamp_gym.tasks.attributes import family_of


def test_families_name_each_train_object_and_leave_the_paper_objects_fitted() -> None:
    scene = suite_scenes(af.TRAIN)[3]
    rows = [{"scene": scene.name, "object": o} for o in scene.object_names]
    rows.append({"scene": "pick-place/001", "object": "mug"})
    fams = af.families(rows)
    assert fams[:-1] == [family_of(scene.object(o).type) for o in scene.object_names]
    assert fams[-1] == "" and all(f and "-v1-" not in f for f in fams[:-1])
    folds = af.family_folds(rows, fams)
    assert len(folds) == len(set(fams[:-1]))
    for fit, held in folds:
        assert len({af.families([r])[0] for r in held}) == 1  # one family held out
        assert rows[-1] in fit and rows[-1] not in held  # the paper's object stays fitted
        assert len(fit) + len(held) == len(rows)


def _row(rng: np.random.Generator, family: int, material: str, k: int) -> dict[str, object]:
    """A synthetic object: its colour says its material (noisily), its size its family."""
    colour = (1.0 if material == MATERIAL_NAMES[0] else -1.0) + rng.normal(0.0, 0.8)
    appearance = {f: float(rng.normal(0.0, 0.1)) for f in FEATURES}
    size = 0.05 + 0.05 * family + rng.normal(0.0, 0.002)
    m: dict[str, object] = {**cylinder_measurements(size), **appearance, FEATURES[0]: colour}
    return {"scene": f"synthetic/{k:04d}", "object": f"obj{k}", "measurements": m,
            "declared": {"material": material, "mass": 0.3, "robustness": "sturdy"}}  # fmt: skip


def test_a_family_that_gives_the_material_away_makes_the_pooling_lean_on_appearance() -> None:
    rng = np.random.default_rng(0)
    a, b = MATERIAL_NAMES[0], MATERIAL_NAMES[1]
    rows, fams = [], []
    for family in range(4):  # each family nearly all one material, alternating
        for k in range(40):
            mat = (a if family % 2 == 0 else b) if k < 36 else (b if family % 2 == 0 else a)
            rows.append(_row(rng, family, mat, len(rows)))
            fams.append(f"family{family}")
    halves = [
        ([r for r in rows if af.index(r) % 2 == p], [r for r in rows if af.index(r) % 2 != p])
        for p in (0, 1)
    ]
    by_family = af.family_folds(rows, fams)
    pool, _, _, acc = af.choose_material((halves, by_family), (1e-3, 1e-3, 1e-3))
    # judged on seen families alone, the size (the family) is the better cue ...
    seen_only, _, _, _ = af.choose_material((halves,), (1e-3, 1e-3, 1e-3))
    assert seen_only > pool
    # ... and over unseen families too, the appearance head carries more weight
    assert pool < 1.0 and acc[f"{pool}/0.0"] > acc["1.0/0.0"]
    model = af.fit(rows, (1e-3, 1e-3, 1e-3), pool=pool)
    assert model.w_appearance is not None and model.pool == pytest.approx(pool)
