"""benchmarks/perceived_procedural.py: the attributes the renders leave ambiguous stand beside
the evidence's ceiling (issue #42's per-attribute line), without running the splits."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

bench = readme.load_script("benchmarks/perceived_procedural.py")


def _table(mass_class: float) -> dict:
    acc = {a: 1.0 for a in bench.ATTRIBUTES} | {"material": 0.9, "mass_class": mass_class}
    stats = {
        "achievable_rate": 1.0, "achievable_ci95": (0.9, 1.0), "achievable_solved": 9,
        "achievable_runs": 9, "achievable_no_plan": 0, "achievable_invalid": 0,
        "unachievable_reported": 1, "unachievable_runs": 1, "affordance_f1": 1.0,
        "crashed": 0, "accuracy": acc, "achievable_by_objects": {"2": (9, 9)}, "scenes": 10,
    }  # fmt: skip
    return {"test-count": {m: dict(stats) for m in bench.METHODS}}


def _ceiling() -> dict:
    def head(ece: float) -> list[dict]:
        return [{"bin": [0.0, 1.0], "n": 3, "confidence": 0.5, "accuracy": 0.5}, {"ece": ece}]

    row = {
        "learned": {"material": 0.88, "robustness": 0.98, "mass": 0.70},
        "handbuilt": {"material": 0.71, "robustness": 0.92, "mass": 0.731},  # the better mass
        "reliability": {"material": head(0.079), "robustness": head(0.083), "mass": head(0.111)},
    }
    return {"commit": "abc1234", "procedural-v1/test-count": {**row, "scenes": 10}}


def test_the_ambiguous_attributes_stand_beside_their_ceiling_and_its_calibration() -> None:
    text = bench._markdown(_table(0.75), (1, 1), _ceiling())
    row = next(line for line in text.splitlines() if line.startswith("| test-count | 0.900 /"))
    assert row == (
        "| test-count | 0.900 / 0.880 (0.079) | 1.000 / 0.980 (0.083) | 0.750 / 0.731 (0.111) "
        "| 10/10 |"
    )  # the ceiling measured on the same scenes as the perceiver
    assert "`abc1234`" in text and "class between the rules' thresholds" in text
    # the per-attribute table carries the mass class beside the mass within a factor 1.5
    header = next(line for line in text.splitlines() if line.startswith("| split | body"))
    assert "| mass | mass_class |" in header


def test_without_an_attribute_model_page_the_page_says_so() -> None:
    text = bench._markdown(_table(0.75), (1, 1), None)
    assert "No attribute-model page to compare with" in text
