"""The paper's results figure (success rate and log-scale planning time, overall and per
object count) and the success-against-F1 plot. Agg backend.

Every success rate is drawn with its 95 % Wilson interval as an error bar; mean planning
times with their 95 % bootstrap interval as error bars, over a ± std band (the spread).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from utamp_gym.provenance import png_metadata

MIN_TIME = 1e-4  # s: the floor of the log axis (a band's lower edge may go below zero)


MARKERS = ("o", "s", "^", "D", "v", "P")


def _integer_ticks(ax: Any, methods: list[dict[str, Any]]) -> None:
    ax.set_xticks(sorted({int(n) for m in methods for n in m["by_objects"]}))


def _methods(summary: dict[str, Any]) -> list[dict[str, Any]]:
    return [m for m in summary["methods"] if m["runs"]]


def _rate_err(stats: list[dict[str, Any]]) -> list[list[float]]:
    """Asymmetric error bars (below, above) of success rates from their Wilson intervals."""
    below, above = [], []
    for d in stats:
        rate, ci = d["success_rate"] or 0.0, d.get("success_rate_ci95")
        below.append(0.0 if ci is None else max(rate - ci[0], 0.0))
        above.append(0.0 if ci is None else max(ci[1] - rate, 0.0))
    return [below, above]


def _mean_err(stats: list[dict[str, Any]], means: list[float]) -> list[list[float]]:
    """Error bars of (floored) mean planning times from their bootstrap intervals."""
    below, above = [], []
    for d, mean in zip(stats, means, strict=True):
        ci = d.get("planning_time_ci95_s")
        below.append(0.0 if ci is None else max(mean - max(ci[0], MIN_TIME), 0.0))
        above.append(0.0 if ci is None else max(ci[1] - mean, 0.0))
    return [below, above]


def _title(summary: dict[str, Any]) -> str:
    return f"{summary.get('suite', '')} suite, {summary.get('grounding', '')} grounding"


def plot_success(summary: dict[str, Any], path: str | Path) -> None:
    """`success_by_objects.png`: overall success per method, and per object count, each
    with its 95 % Wilson interval."""
    methods = _methods(summary)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4), gridspec_kw={"width_ratios": [1, 1.4]})
    labels = [f"{m['label']}\n(n={m['runs']})" for m in methods]
    colors = [f"C{i}" for i in range(len(methods))]
    left.bar(
        range(len(methods)),
        [m["success_rate"] or 0.0 for m in methods],
        yerr=_rate_err(methods),
        capsize=4,
        color=colors,
    )
    left.set_xticks(range(len(methods)), labels, rotation=30, ha="right")
    left.set_ylabel("success rate")
    left.set_title("overall (95 % Wilson CI)")
    for i, (m, c) in enumerate(zip(methods, colors, strict=True)):
        ns = sorted(m["by_objects"], key=int)
        by_n = [m["by_objects"][n] for n in ns]
        shift = 0.06 * (i - (len(methods) - 1) / 2)  # keep coinciding lines visible
        right.errorbar(
            [int(n) + shift for n in ns],
            [d["success_rate"] for d in by_n],
            yerr=_rate_err(by_n),
            fmt=MARKERS[i % len(MARKERS)] + "-",
            color=c,
            lw=2,
            capsize=3,
            label=m["label"],
        )
    _integer_ticks(right, methods)
    left.set_ylim(-0.02, 1.05)
    right.set_ylim(-0.02, 1.05)
    right.set_xlabel("number of objects")
    right.set_ylabel("success rate")
    right.set_title("per object count (95 % Wilson CI)")
    right.legend(fontsize=8)
    fig.suptitle(_title(summary))
    fig.tight_layout()
    fig.savefig(path, dpi=120, metadata=png_metadata(summary))
    plt.close(fig)


def plot_planning_time(summary: dict[str, Any], path: str | Path) -> None:
    """`planning_time_by_objects.png`: log-scale mean, overall and per object count: the 95 %
    bootstrap interval of the mean as error bars, ± std as a thin bar (left) or band (right)."""
    methods = [m for m in _methods(summary) if m["planning_time_mean_s"] is not None]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4), gridspec_kw={"width_ratios": [1, 1.4]})
    for i, m in enumerate(methods):
        mean, std = max(m["planning_time_mean_s"], MIN_TIME), m["planning_time_std_s"]
        left.errorbar(  # the spread: ± std, thin
            [i], [mean], yerr=[[mean - max(mean - std, MIN_TIME)], [std]], color=f"C{i}", lw=1
        )
        left.errorbar(  # the mean's 95 % interval, bold
            [i], [mean], yerr=_mean_err([m], [mean]), fmt="o", color=f"C{i}", capsize=6, lw=3
        )
        ns = [
            n
            for n in sorted(m["by_objects"], key=int)
            if m["by_objects"][n]["planning_time_mean_s"] is not None
        ]
        by_n = [m["by_objects"][n] for n in ns]
        x = [int(n) for n in ns]
        mu = [max(d["planning_time_mean_s"], MIN_TIME) for d in by_n]
        sd = [d["planning_time_std_s"] for d in by_n]
        right.errorbar(
            x,
            mu,
            yerr=_mean_err(by_n, mu),
            fmt=MARKERS[i % len(MARKERS)] + "-",
            color=f"C{i}",
            lw=2.5,
            capsize=4,
            label=m["label"],
        )
        right.fill_between(
            x,
            [max(a - b, MIN_TIME) for a, b in zip(mu, sd, strict=True)],
            [a + b for a, b in zip(mu, sd, strict=True)],
            color=f"C{i}",
            alpha=0.2,
        )
    left.set_xticks(range(len(methods)), [m["label"] for m in methods], rotation=30, ha="right")
    for ax in (left, right):
        ax.set_yscale("log")
        ax.set_ylabel("planning time (s)")
    left.set_title("overall (mean, 95 % CI bold, ± std thin)")
    right.set_xlabel("number of objects")
    _integer_ticks(right, methods)
    right.set_title("per object count (mean, 95 % CI bars, ± std band)")
    if methods:
        right.legend(fontsize=8)
    fig.suptitle(_title(summary))
    fig.tight_layout()
    fig.savefig(path, dpi=120, metadata=png_metadata(summary))
    plt.close(fig)


def plot_success_vs_f1(summary: dict[str, Any], path: str | Path) -> None:
    """`success_vs_f1.png`: success rate against the mean affordance F1 of each noise level."""
    sweep = [s for s in summary["noise_sweep"] if s["affordance_f1_mean"] is not None]
    fig, ax = plt.subplots(figsize=(6, 4))
    f1 = [s["affordance_f1_mean"] for s in sweep]
    ax.errorbar(
        f1,
        [s["success_rate"] for s in sweep],
        yerr=_rate_err(sweep),
        fmt="o-",
        lw=2,
        capsize=4,
        color="C2",
    )
    for s in sweep:
        ax.annotate(
            f"p={s['noise']:g}",
            (s["affordance_f1_mean"], s["success_rate"]),
            textcoords="offset points",
            xytext=(4, 4),
            fontsize=8,
        )
    ax.set_xlabel("mean affordance F1 (utamp2-noisy)")
    ax.set_ylabel("success rate (95 % Wilson CI)")
    ax.set_ylim(-0.02, 1.05)
    ax.set_title(_title(summary))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120, metadata=png_metadata(summary))
    plt.close(fig)


def write_plots(out: str | Path, summary: dict[str, Any]) -> list[Path]:
    """Write the figures into `out`; returns their paths."""
    out = Path(out)
    paths = [out / "success_by_objects.png", out / "planning_time_by_objects.png"]
    plot_success(summary, paths[0])
    plot_planning_time(summary, paths[1])
    if summary["noise_sweep"]:
        paths.append(out / "success_vs_f1.png")
        plot_success_vs_f1(summary, paths[2])
    return paths
