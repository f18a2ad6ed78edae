"""The paper's results table from result rows: success rate and planning time per method.

Statistics are per method (``utamp2-noisy`` per noise level), overall and per object
count; planning time is mean ± sample standard deviation over all runs that reached
the planner. Written as ``summary.json`` (machine-readable) and ``summary.md``.
"""

from __future__ import annotations

import json
import os
import re
import statistics
from collections import Counter
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from utamp_gym.eval.records import ResultRow
from utamp_gym.eval.runner import EVAL_METHODS

_PRECONDITION = re.compile(r"precondition \((\S+)")


def group_label(row: ResultRow) -> str:
    return row.method if row.noise is None else f"{row.method} (p={row.noise:g})"


def _mean_std(xs: Sequence[float]) -> tuple[float | None, float | None]:
    if not xs:
        return None, None
    return statistics.fmean(xs), (statistics.stdev(xs) if len(xs) > 1 else 0.0)


def failure_category(reason: str) -> str:
    """A short class of a failure reason, e.g. ``violates isP2PSupportive``."""
    if reason.startswith("crashed"):
        return "crashed"
    m = _PRECONDITION.search(reason)
    if reason.startswith("invalid under ground truth") and m:
        return f"invalid plan: violates {m.group(1)}"
    if reason.startswith("not solved: VLM"):
        return "unusable VLM answer"
    if reason.startswith("not solved"):
        return "no plan found"
    if reason.startswith("step"):
        return "execution failed"
    return reason.split(":", 1)[0][:60]


def stats(rows: Sequence[ResultRow]) -> dict[str, Any]:
    """Success rate, planning time mean/std and affordance scores of some rows."""
    times = [r.planning_time_s for r in rows if r.planning_time_s is not None]
    t_mean, t_std = _mean_std(times)
    f1 = [r.affordance_f1 for r in rows if r.affordance_f1 is not None]
    valid = [r for r in rows if r.valid_gt is not None]
    return {
        "runs": len(rows),
        "success_rate": sum(r.success for r in rows) / len(rows) if rows else None,
        "solved_rate": sum(r.solved for r in rows) / len(rows) if rows else None,
        "valid_plan_rate": sum(bool(r.valid_gt) for r in valid) / len(valid) if valid else None,
        "planning_time_mean_s": t_mean,
        "planning_time_std_s": t_std,
        "execution_time_mean_s": _mean_std([r.execution_time_s for r in rows])[0],
        "affordance_f1_mean": statistics.fmean(f1) if f1 else None,
        "crashed": sum(r.crashed for r in rows),
    }


def _order(label: str) -> tuple[int, str]:
    method = label.split(" ", 1)[0]
    return (EVAL_METHODS.index(method) if method in EVAL_METHODS else 99, label)


def summarize(
    rows: Iterable[ResultRow], *, context: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The summary document: per method overall and per object count, plus a noise sweep."""
    rows = list(rows)
    groups: dict[str, list[ResultRow]] = {}
    for r in rows:
        groups.setdefault(group_label(r), []).append(r)
    methods = []
    for label in sorted(groups, key=_order):
        g = groups[label]
        by_n = {
            str(n): stats([r for r in g if r.n_objects == n])
            for n in sorted({r.n_objects for r in g})
        }
        failures = Counter(failure_category(r.failure_reason) for r in g if not r.success)
        methods.append(
            {
                "label": label,
                "method": g[0].method,
                "noise": g[0].noise,
                **stats(g),
                "by_objects": by_n,
                "failures": dict(failures.most_common()),
            }
        )
    noisy = sorted({r.noise for r in rows if r.method == "utamp2-noisy" and r.noise is not None})
    sweep = []
    if len(noisy) > 1:
        for p in noisy:
            g = [r for r in rows if r.method == "utamp2-noisy" and r.noise == p]
            st = stats(g)
            prec = [r.affordance_precision for r in g if r.affordance_precision is not None]
            rec = [r.affordance_recall for r in g if r.affordance_recall is not None]
            sweep.append(
                {
                    "noise": p,
                    "runs": st["runs"],
                    "affordance_f1_mean": st["affordance_f1_mean"],
                    "affordance_precision_mean": statistics.fmean(prec) if prec else None,
                    "affordance_recall_mean": statistics.fmean(rec) if rec else None,
                    "success_rate": st["success_rate"],
                    "solved_rate": st["solved_rate"],
                }
            )
    return {**(context or {}), "runs": len(rows), "methods": methods, "noise_sweep": sweep}


def _f(x: float | None, spec: str = ".2f") -> str:
    return "–" if x is None else format(x, spec)


def _time(d: dict[str, Any]) -> str:
    m, s = d["planning_time_mean_s"], d["planning_time_std_s"]
    return "–" if m is None else f"{m:.3f} ± {s:.3f}"


def to_markdown(summary: dict[str, Any]) -> str:
    """`summary.md`: the table of the paper plus per-object-count and failure breakdowns."""
    suite, grounding = summary.get("suite", "?"), summary.get("grounding", "?")
    out = [f"# Evaluation: {suite} suite, {grounding} grounding", ""]
    out.append(
        f"{summary['runs']} runs ({summary.get('scenes', '?')} scenes, "
        f"{summary.get('seeds', '?')} seed(s)); success = "
        + (
            "plan valid under the ground-truth U-TAMP-2 model."
            if grounding == "symbolic"
            else "every step executed in MuJoCo and the tower stands on the tray."
        )
    )
    out += [f"- note: {n}" for n in summary.get("notes", [])]
    out += ["", "## Success rate and planning time", ""]
    out += [
        "| method | runs | success rate | planning time (s) | valid plans | affordance F1 "
        "| crashed |",
        "|---|---|---|---|---|---|---|",
    ]
    for m in summary["methods"]:
        out.append(
            f"| {m['label']} | {m['runs']} | {_f(m['success_rate'])} | {_time(m)} | "
            f"{_f(m['valid_plan_rate'])} | {_f(m['affordance_f1_mean'], '.3f')} | {m['crashed']} |"
        )
    ns = sorted({n for m in summary["methods"] for n in m["by_objects"]}, key=int)
    for title, cell in (
        ("Success rate per object count", lambda d: _f(d["success_rate"])),
        ("Planning time (s) per object count", _time),
    ):
        out += ["", f"## {title}", "", "| method | " + " | ".join(f"n={n}" for n in ns) + " |"]
        out.append("|---|" + "---|" * len(ns))
        for m in summary["methods"]:
            cells = [cell(m["by_objects"][n]) if n in m["by_objects"] else "–" for n in ns]
            out.append(f"| {m['label']} | " + " | ".join(cells) + " |")
    if summary["noise_sweep"]:
        out += ["", "## Success rate against affordance F1 (utamp2-noisy)", ""]
        out += [
            "| noise p | runs | F1 | precision | recall | success rate |",
            "|---|---|---|---|---|---|",
        ]
        for s in summary["noise_sweep"]:
            out.append(
                f"| {s['noise']:g} | {s['runs']} | {_f(s['affordance_f1_mean'], '.3f')} | "
                f"{_f(s['affordance_precision_mean'], '.3f')} | "
                f"{_f(s['affordance_recall_mean'], '.3f')} | {_f(s['success_rate'])} |"
            )
    out += ["", "## Failures", ""]
    for m in summary["methods"]:
        if m["failures"]:
            shown = ", ".join(f"{k} ×{v}" for k, v in m["failures"].items())
            out.append(f"- {m['label']}: {shown}")
    return "\n".join(out) + "\n"


def write_summary(out: str | Path, summary: dict[str, Any]) -> None:
    """Write ``summary.json`` and ``summary.md`` into `out`."""
    out = Path(out)
    for name, text in (
        ("summary.json", json.dumps(summary, indent=2) + "\n"),
        ("summary.md", to_markdown(summary)),
    ):
        tmp = out / f".{name}.tmp"
        tmp.write_text(text)
        os.replace(tmp, out / name)
