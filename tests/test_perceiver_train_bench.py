"""benchmarks/perceiver_train.py: the page calls maps shipped only when the package ships
them; an earlier run's maps, which the perceiver applies, are measured beside this run's."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import numpy as np
import perceiver_train as pt
import pytest

from utamp_gym.perception.confidence import packaged_calibration


def test_maps_are_called_shipped_only_when_the_package_ships_them() -> None:
    fitted = pt.reliability_tables("fitted", ["mass", "members"])
    assert [k for _, k in fitted] == ["reliability_raw", "reliability"]
    assert fitted[1][0] == "shipped (maps for mass, members, fitted by this run)"
    other = pt.reliability_tables("other", ["mass"])
    assert [k for _, k in other] == ["reliability_raw", "reliability", "reliability_shipped"]
    assert other[1][0].startswith("fitted by this run but not shipped")
    assert "earlier run" in other[2][0] and "--write-calibration" in other[2][0]
    none = pt.reliability_tables("none", [])
    assert [k for _, k in none] == ["reliability_raw", "reliability"]
    assert none[1][0] == "fitted by this run but not shipped (maps for none)"


@pytest.mark.slow
def test_the_shipped_calibration_is_what_the_script_fits_on_the_current_perceiver(
    tmp_path: Path,
) -> None:
    """The shipped maps come out of ``perceiver_train.py --write-calibration`` on the raw
    confidences the perceiver gives now: a perceiver change that moves them asks for a refit."""
    cal, _ = pt.fit_calibration(pt.collect(tmp_path, None))
    shipped = packaged_calibration()
    assert shipped is not None
    made, have = cal.to_json(), shipped.to_json()
    assert made.keys() == have.keys()
    for attribute, knots in have.items():
        for key, values in knots.items():
            np.testing.assert_allclose(made[attribute][key], values, atol=1e-6)
