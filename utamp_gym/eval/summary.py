"""The paper's results table from result rows: success rate and planning time per method.

Statistics are per method (``utamp2-noisy`` per noise level), overall and per object
count; planning time is mean ± sample standard deviation over all runs that reached
the planner. Every rate comes with its number of runs and a 95 % Wilson interval
(``success_rate_ci95``), the mean planning and execution times with a seeded 95 %
bootstrap interval (``planning_time_ci95_s``, ``execution_time_ci95_s``). Written as
``summary.json`` (machine-readable) and ``summary.md``.
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

from utamp_gym.eval.intervals import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    bootstrap_mean_interval,
    wilson_interval,
)
from utamp_gym.eval.records import ResultRow
from utamp_gym.eval.runner import EVAL_METHODS
from utamp_gym.eval.stages import ATTRIBUTE_COLUMNS, ATTRIBUTES, STAGES
from utamp_gym.provenance import provenance, with_footer
from utamp_gym.suites import SUITES

_PRECONDITION = re.compile(r"precondition \((\S+)")
#: a symbolic step the outcome model refused:
#: "step I (ACTION): [not ]PRED(ARGS) is false (ground truth)"
_GROUND_TRUTH = re.compile(r"^step \d+ .*?: (?:not )?(\w+)\(.*\) is false \(ground truth\)$")


def group_label(row: ResultRow) -> str:
    label = row.method if row.noise is None else f"{row.method} (p={row.noise:g})"
    return label if row.perception == "gaussian" else f"{label} [{row.perception}]"


def _mean_std(xs: Sequence[float]) -> tuple[float | None, float | None]:
    if not xs:
        return None, None
    return statistics.fmean(xs), (statistics.stdev(xs) if len(xs) > 1 else 0.0)


def failure_category(reason: str) -> str:
    """A short class of a failure reason, e.g. ``violates isP2PSupportive``."""
    if reason.startswith("crashed"):
        return "crashed"
    m = _PRECONDITION.search(reason)
    if reason.startswith("invalid under ground truth") and m:  # rows written before 2026-11
        return f"invalid plan: violates {m.group(1)}"
    truth = _GROUND_TRUTH.match(reason)
    if truth:
        return f"invalid plan: violates {truth.group(1)}"
    if reason.startswith("step") and m and reason.endswith(("(static)", "(fluent)")):
        return f"invalid plan: violates {m.group(1)}"  # symbolic: a false precondition
    if reason.startswith("not solved: VLM"):
        return "unusable VLM answer"
    if reason.startswith("not solved"):
        return "no plan found"
    if reason.startswith("step"):
        return "execution failed"
    return reason.split(":", 1)[0][:60]


def _interval(ci: tuple[float, float] | None) -> list[float] | None:
    return None if ci is None else [ci[0], ci[1]]


def stats(rows: Sequence[ResultRow]) -> dict[str, Any]:
    """Success rate (n, Wilson 95 %), planning/execution time (mean, std, bootstrap 95 %),
    affordance scores of some rows."""
    times = [r.planning_time_s for r in rows if r.planning_time_s is not None]
    t_mean, t_std = _mean_std(times)
    exec_times = [r.execution_time_s for r in rows]
    f1 = [r.affordance_f1 for r in rows if r.affordance_f1 is not None]
    valid = [r for r in rows if r.valid_gt is not None]
    successes = sum(r.success for r in rows)
    return {
        "runs": len(rows),
        "successes": successes,
        "success_rate": successes / len(rows) if rows else None,
        "success_rate_ci95": _interval(wilson_interval(successes, len(rows))),
        "solved_rate": sum(r.solved for r in rows) / len(rows) if rows else None,
        "valid_plan_rate": sum(bool(r.valid_gt) for r in valid) / len(valid) if valid else None,
        "planning_time_mean_s": t_mean,
        "planning_time_std_s": t_std,
        "planning_time_runs": len(times),
        "planning_time_ci95_s": _interval(bootstrap_mean_interval(times)),
        "execution_time_mean_s": _mean_std(exec_times)[0],
        "execution_time_ci95_s": _interval(bootstrap_mean_interval(exec_times)),
        "affordance_f1_mean": statistics.fmean(f1) if f1 else None,
        "crashed": sum(r.crashed for r in rows),
    }


def _attributes(rows: Sequence[ResultRow]) -> dict[str, float] | None:
    """Mean per-attribute accuracy over the rows that have it (None: no detected attributes)."""
    out = {}
    for a, col in zip(ATTRIBUTES, ATTRIBUTE_COLUMNS, strict=True):
        vals = [getattr(r, col) for r in rows if getattr(r, col) is not None]
        if vals:
            out[a] = statistics.fmean(vals)
    return out or None


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
        stages = Counter(r.failure_stage or "unknown" for r in g if not r.success)
        methods.append(
            {
                "label": label,
                "method": g[0].method,
                "noise": g[0].noise,
                **stats(g),
                "by_objects": by_n,
                "failures": dict(failures.most_common()),
                "failure_stages": {st: stages[st] for st in (*STAGES, "unknown") if stages[st]},
                "attribute_accuracy": _attributes(g),
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
                    "successes": st["successes"],
                    "success_rate": st["success_rate"],
                    "success_rate_ci95": st["success_rate_ci95"],
                    "solved_rate": st["solved_rate"],
                }
            )
    return {**(context or {}), "runs": len(rows), "methods": methods, "noise_sweep": sweep}


def _f(x: float | None, spec: str = ".2f") -> str:
    return "–" if x is None else format(x, spec)


def _ci(ci: list[float] | None, spec: str = ".2f") -> str:
    return "–" if ci is None else f"{ci[0]:{spec}}–{ci[1]:{spec}}"


def _time(d: dict[str, Any]) -> str:
    m, s = d["planning_time_mean_s"], d["planning_time_std_s"]
    return "–" if m is None else f"{m:.3f} ± {s:.3f}"


def _rate_n(d: dict[str, Any]) -> str:
    """``0.95 (0.76–0.99, n=20)``: a success rate with its Wilson interval and n."""
    if d["success_rate"] is None:
        return "–"
    return f"{d['success_rate']:.2f} ({_ci(d.get('success_rate_ci95'))}, n={d['runs']})"


def _time_ci(d: dict[str, Any]) -> str:
    """``0.052 ± 0.015 [0.049–0.055]``: mean ± std [bootstrap interval of the mean]."""
    if d["planning_time_mean_s"] is None:
        return "–"
    return f"{_time(d)} [{_ci(d.get('planning_time_ci95_s'), '.3f')}]"


def _exec(d: dict[str, Any]) -> str:
    m = d["execution_time_mean_s"]
    return "–" if m is None else f"{m:.2f} [{_ci(d.get('execution_time_ci95_s'))}]"


def _header(summary: dict[str, Any]) -> list[str]:
    suite, grounding = summary.get("suite", "?"), summary.get("grounding", "?")
    seeds = f"{summary.get('seeds', '?')} seed(s)"
    if summary.get("seed_offset"):
        seeds += f" from {summary['seed_offset']}"
    out = [f"# Evaluation: {suite} suite, {grounding} grounding", ""]
    out.append(
        f"{summary['runs']} runs ({summary.get('scenes', '?')} scenes, {seeds}); success = "
        + (
            "the plan played in the symbolic env, every step's U-TAMP-2 precondition true "
            "under the ground truth, and the goal reached."
            if grounding == "symbolic"
            else "every step executed in MuJoCo and the tower stands on "
            + ("the tray." if suite in SUITES else "each scene's base object (`goal_base`).")
        )
    )
    out.append(
        "Intervals are 95 %: Wilson score for rates, percentile bootstrap "
        f"({BOOTSTRAP_RESAMPLES} resamples, seed {BOOTSTRAP_SEED}) for mean times."
    )
    if summary.get("scene_pattern"):
        out.append(f"- scenes matching `{summary['scene_pattern']}`")
    if summary.get("shard"):
        out.append(f"- shard {summary['shard']} of the sweep")
    if summary.get("merged_from"):
        out.append("- merged from: " + ", ".join(f"`{d}`" for d in summary["merged_from"]))
    out += [f"- note: {n}" for n in summary.get("notes", [])]
    return out


def to_markdown(summary: dict[str, Any]) -> str:
    """`summary.md`: the table of the paper plus per-object-count and failure breakdowns."""
    out = _header(summary)
    out += ["", "## Success rate and planning time", ""]
    out += [
        "| method | runs | success rate | 95 % CI | planning time (s) | mean 95 % CI "
        "| execution time (s) [95 % CI] | valid plans | affordance F1 | crashed |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for m in summary["methods"]:
        out.append(
            f"| {m['label']} | {m['runs']} | {_f(m['success_rate'])} | "
            f"{_ci(m.get('success_rate_ci95'))} | {_time(m)} | "
            f"{_ci(m.get('planning_time_ci95_s'), '.3f')} | {_exec(m)} | "
            f"{_f(m['valid_plan_rate'])} | {_f(m['affordance_f1_mean'], '.3f')} | {m['crashed']} |"
        )
    ns = sorted({n for m in summary["methods"] for n in m["by_objects"]}, key=int)
    for title, cell in (
        ("Success rate per object count (95 % CI, n)", _rate_n),
        ("Planning time (s) per object count: mean ± std [95 % CI of the mean]", _time_ci),
    ):
        out += ["", f"## {title}", "", "| method | " + " | ".join(f"n={n}" for n in ns) + " |"]
        out.append("|---|" + "---|" * len(ns))
        for m in summary["methods"]:
            cells = [cell(m["by_objects"][n]) if n in m["by_objects"] else "–" for n in ns]
            out.append(f"| {m['label']} | " + " | ".join(cells) + " |")
    if summary["noise_sweep"]:
        out += ["", "## Success rate against affordance F1 (utamp2-noisy)", ""]
        out += [
            "| noise p | runs | F1 | precision | recall | success rate | 95 % CI |",
            "|---|---|---|---|---|---|---|",
        ]
        for s in summary["noise_sweep"]:
            out.append(
                f"| {s['noise']:g} | {s['runs']} | {_f(s['affordance_f1_mean'], '.3f')} | "
                f"{_f(s['affordance_precision_mean'], '.3f')} | "
                f"{_f(s['affordance_recall_mean'], '.3f')} | {_f(s['success_rate'])} | "
                f"{_ci(s.get('success_rate_ci95'))} |"
            )
    detected = [m for m in summary["methods"] if m.get("attribute_accuracy")]
    if detected:
        out += ["", "## Per-attribute accuracy (detected attributes)", ""]
        out += ["| method | " + " | ".join(ATTRIBUTES) + " |"]
        out.append("|---|" + "---|" * len(ATTRIBUTES))
        for m in detected:
            acc = m["attribute_accuracy"]
            cells = [_f(acc.get(a), ".3f") for a in ATTRIBUTES]
            out.append(f"| {m['label']} | " + " | ".join(cells) + " |")
    out += ["", "## Failures by stage", ""]
    out += [
        "A failed run is charged to the first stage that went wrong: `perception` (detected "
        "attributes gave wrong affordances that lost the plan), `affordances` (the rules did), "
        "`plan` (no valid plan with right affordances), `physics` (a valid plan failed in "
        "execution), `crash`.",
        "",
        "| method | failed | " + " | ".join(STAGES) + " |",
        "|---|---|" + "---|" * len(STAGES),
    ]
    for m in summary["methods"]:
        st = m.get("failure_stages", {})
        failed = m["runs"] - m["successes"]
        out.append(
            f"| {m['label']} | {failed} | " + " | ".join(str(st.get(k, 0)) for k in STAGES) + " |"
        )
    out += ["", "## Failures", ""]
    for m in summary["methods"]:
        if m["failures"]:
            shown = ", ".join(f"{k} ×{v}" for k, v in m["failures"].items())
            out.append(f"- {m['label']}: {shown}")
    text = "\n".join(out) + "\n"
    if "command" in summary and "commit" in summary:
        text = with_footer(text, {"command": summary["command"], "commit": summary["commit"]})
    return text


def write_summary(out: str | Path, summary: dict[str, Any]) -> None:
    """Write ``summary.json`` and ``summary.md`` into `out`.

    The provenance of this process (`utamp_gym.provenance`: ``commit``, ``command``) is added
    to `summary` first, unless it has one already."""
    out = Path(out)
    for key, value in provenance().items():
        summary.setdefault(key, value)
    for name, text in (
        ("summary.json", json.dumps(summary, indent=2) + "\n"),
        ("summary.md", to_markdown(summary)),
    ):
        tmp = out / f".{name}.tmp"
        tmp.write_text(text)
        os.replace(tmp, out / name)
