"""95 % confidence intervals for the summaries: Wilson for rates, bootstrap for means, and
Student's t for a mean over a few seeds (`t_interval`, the benchmarks').

The Wilson score interval stays inside [0, 1] and is sensible at 0 % and 100 % with few
runs, where the normal approximation collapses to a point. Mean times are skewed (a few
slow five-object runs), so their interval is a percentile bootstrap with a fixed seed:
the same rows always give the same interval.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence

import numpy as np

Z95 = 1.959963984540054  # the standard normal's 97.5 % quantile
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 0
#: Student t's 97.5 % quantile by degrees of freedom (`t_interval`)
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571}
_CHUNK = 4_000_000  # resampled values per numpy batch (bounds memory for large sweeps)


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float] | None:
    """The Wilson score interval of a rate `successes`/`n` (None without runs)."""
    if n <= 0:
        return None
    if not 0 <= successes <= n:
        raise ValueError(f"successes must be in [0, {n}], got {successes}")
    p = successes / n
    z2 = z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    low = 0.0 if successes == 0 else max(0.0, centre - half)  # exact at the ends
    high = 1.0 if successes == n else min(1.0, centre + half)
    return low, high


def bootstrap_mean_interval(
    values: Sequence[float],
    *,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
    level: float = 0.95,
) -> tuple[float, float] | None:
    """Percentile bootstrap interval of the mean of `values` (None when empty).

    Seeded, and the values are sorted first, so equal multisets of values (e.g. the rows
    of a merged sweep, in another order) give the same interval.
    """
    x = np.sort(np.asarray(values, dtype=float))
    if x.size == 0:
        return None
    rng = np.random.default_rng(seed)
    means = np.empty(resamples)
    batch = max(1, _CHUNK // x.size)
    for start in range(0, resamples, batch):
        stop = min(resamples, start + batch)
        means[start:stop] = x[rng.integers(0, x.size, size=(stop - start, x.size))].mean(axis=1)
    tail = (1.0 - level) / 2 * 100
    low, high = np.percentile(means, [tail, 100 - tail])
    return float(low), float(high)


def t_interval(values: Sequence[float]) -> tuple[float, float]:
    """(mean, 95 % half-width) of a few values, e.g. one rate per seed (at most six: `T95`;
    the half-width is NaN for one value)."""
    mean = statistics.fmean(values)
    if len(values) < 2:
        return mean, float("nan")
    if len(values) - 1 not in T95:
        raise ValueError(f"t_interval takes 1 to {max(T95) + 1} values, got {len(values)}")
    return mean, T95[len(values) - 1] * statistics.stdev(values) / math.sqrt(len(values))
