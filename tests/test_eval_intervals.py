"""95 % intervals: Wilson (published values), bootstrap (seeded, order-free), and the summary
and figures that carry them."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from utamp_gym.eval.intervals import bootstrap_mean_interval, t_interval, wilson_interval
from utamp_gym.eval.plots import write_plots
from utamp_gym.eval.records import ResultRow
from utamp_gym.eval.summary import summarize, to_markdown, write_summary


@pytest.mark.parametrize(
    ("k", "n", "low", "high"),
    [  # Newcombe (1998), Stat. Med. 17:857, Table I, method 3 (Wilson score, no correction)
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ],
)
def test_wilson_interval_matches_published_values(k: int, n: int, low: float, high: float):
    lo, hi = wilson_interval(k, n)  # type: ignore[misc]
    assert lo == pytest.approx(low, abs=5e-5) and hi == pytest.approx(high, abs=5e-5)


def test_wilson_interval_edges() -> None:
    assert wilson_interval(0, 0) is None
    lo, hi = wilson_interval(10, 10)  # type: ignore[misc]
    assert hi == 1.0 and lo == pytest.approx(0.7225, abs=5e-5)  # not the degenerate [1, 1]
    lo, hi = wilson_interval(5, 10)  # type: ignore[misc]
    assert lo == pytest.approx(1 - hi) and lo == pytest.approx(0.2366, abs=5e-5)
    with pytest.raises(ValueError, match="successes must be in"):
        wilson_interval(11, 10)


def test_bootstrap_is_seeded_and_order_free() -> None:
    rng = np.random.default_rng(7)
    xs = list(rng.lognormal(-3.0, 0.5, size=57))
    first = bootstrap_mean_interval(xs)
    assert first == bootstrap_mean_interval(xs)  # deterministic
    assert first == bootstrap_mean_interval(xs[::-1])  # the order of the rows does not matter
    assert first != bootstrap_mean_interval(xs, seed=1)  # the seed is what fixes it
    lo, hi = first  # type: ignore[misc]
    assert lo < float(np.mean(xs)) < hi
    assert bootstrap_mean_interval([]) is None
    assert bootstrap_mean_interval([0.25]) == (0.25, 0.25)
    assert bootstrap_mean_interval([0.1] * 5) == pytest.approx((0.1, 0.1))


def test_bootstrap_agrees_with_the_normal_interval_for_many_samples() -> None:
    xs = np.random.default_rng(3).normal(2.0, 0.5, size=1000)
    lo, hi = bootstrap_mean_interval(list(xs))  # type: ignore[misc]
    half = 1.96 * xs.std(ddof=1) / math.sqrt(xs.size)
    assert (hi - lo) / 2 == pytest.approx(half, rel=0.1)
    assert (lo + hi) / 2 == pytest.approx(xs.mean(), abs=0.2 * half)


def _row(scene: str, n: int, success: bool, planning: float, **kw: object) -> ResultRow:
    base = ResultRow(
        scene=scene,
        suite="pick-place",
        n_objects=n,
        method="utamp2-gt",
        seed=0,
        grounding="physics",
        noise=None,
        solved=True,
        success=success,
        failure_reason="" if success else "step 1 pick: dropped",
        plan_length=4,
        planning_time_s=planning,
        execution_time_s=1.0 + planning,
        wall_time_s=2.0,
        affordance_precision=1.0,
        affordance_recall=1.0,
        affordance_f1=1.0,
    )
    return replace(base, **kw)  # type: ignore[arg-type]


def test_summary_and_plots_carry_n_and_intervals(tmp_path: Path) -> None:
    rows = [_row(f"pick-place/{i:03d}", 2, i < 4, 0.03 + 0.001 * i) for i in range(5)]
    rows += [_row(f"pick-place/{i:03d}", 3, i % 2 == 0, 0.05 + 0.002 * i) for i in range(5, 15)]
    noisy = [
        _row(r.scene, r.n_objects, r.success and p == 0.0, 0.04, method="utamp2-noisy", noise=p)
        for p in (0.0, 0.1)
        for r in rows
    ]
    summary = summarize(rows + noisy, context={"suite": "pick-place", "grounding": "physics"})
    gt = summary["methods"][0]
    assert gt["label"] == "utamp2-gt" and (gt["runs"], gt["successes"]) == (15, 9)
    assert gt["success_rate_ci95"] == list(wilson_interval(9, 15))  # type: ignore[arg-type]
    two = gt["by_objects"]["2"]
    assert two["runs"] == 5 and two["success_rate_ci95"] == list(wilson_interval(4, 5))  # type: ignore[arg-type]
    times = [r.planning_time_s for r in rows if r.n_objects == 2]
    assert two["planning_time_ci95_s"] == list(bootstrap_mean_interval(times))  # type: ignore[arg-type,arg-type]
    lo, hi = gt["execution_time_ci95_s"]
    assert lo < gt["execution_time_mean_s"] < hi
    for key in ("success_rate", "planning_time_mean_s", "planning_time_std_s"):  # kept as before
        assert key in gt and key in two
    sweep = summary["noise_sweep"]
    assert [s["noise"] for s in sweep] == [0.0, 0.1]
    assert sweep[1]["successes"] == 0 and sweep[1]["success_rate_ci95"][0] == 0.0
    md = to_markdown(summary)
    assert "| utamp2-gt | 15 | 0.60 | 0.36–0.80 |" in md
    assert "0.80 (0.38–0.96, n=5)" in md  # per object count: rate (Wilson, n)
    write_summary(tmp_path, summary)
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    paths = write_plots(tmp_path, summary)
    assert [p.name for p in paths] == [
        "success_by_objects.png",
        "planning_time_by_objects.png",
        "success_vs_f1.png",
    ]
    assert all(p.stat().st_size > 0 for p in paths)


def test_t_interval_of_a_few_seeds() -> None:
    """Student t with n - 1 degrees of freedom: (mean, half-width); one value has none."""
    mean, half = t_interval([0.5, 0.7, 0.6])
    assert mean == pytest.approx(0.6) and half == pytest.approx(4.303 * 0.1 / 3**0.5)
    assert math.isnan(t_interval([0.4])[1]) and t_interval([0.4])[0] == 0.4
    assert t_interval([0.3] * 6)[1] == 0.0
    with pytest.raises(ValueError, match="1 to 6 values"):
        t_interval([0.1] * 7)
