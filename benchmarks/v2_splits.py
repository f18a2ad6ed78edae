"""The procedural-v2 split file against issue #38's lines, relabelled by the current code.

    nice -n 5 python benchmarks/v2_splits.py [--workers 2] [--no-fd] [--results docs/results]

Reads ``assets/procedural/procedural-v2.toml`` and writes ``docs/results/procedural_splits_v2.md``
and ``.json``: per split its scenes, achievable and unachievable goals, plan lengths, goals per
template, the seed after which its template quotas were relaxed and its digest; then every
scene relabelled by the labeller as the code is now (`labels.label`) and, unless ``--no-fd``,
checked against Fast Downward's own translator (`labels.fd_agrees`), with every label that
differs listed; and the issue's lines, each met or not: each split >= 100 scenes (train >=
400; ``hard`` is a suite of its own), 5-15 % unachievable (``hard``: none, every plan >= 12
actions), every template >= 20 achievable scenes across the splits only evaluated on (the
test splits and ``hard``, which alone draws ``restack``), ``test-tasks`` holds >= 2
templates absent from ``train``, every label agrees with the planner and Fast Downward's
translator.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results

from utamp_gym.provenance import commit
from utamp_gym.suites.procedural_v2 import available_splits, split_scene, split_seeds
from utamp_gym.suites.procedural_v2.labels import fd_agrees, label
from utamp_gym.suites.procedural_v2.seeds import _seed_table
from utamp_gym.suites.procedural_v2.spec import HARD_MIN_ACTIONS, SPLIT_TEMPLATES
from utamp_gym.tasks.templates import parts

MIN_SCENES = {"train": 400, "hard": 1}  # the issue's sizes (hard: a suite of its own)
SHARE = (0.05, 0.15)  # unachievable goals per split (hard: none)
MIN_PER_TEMPLATE = 20  # achievable scenes of every template across the evaluation splits
#: the splits only evaluated on: the test splits and the hard suite (whose own template,
#: ``restack``, no test split draws)
EVALUATED = ("test-instances", "test-families", "test-count", "test-tasks", "hard")
#: the templates (and parts of compositions) the evaluation splits draw from
TEMPLATES_TESTED = sorted(
    {p for s, ts in SPLIT_TEMPLATES.items() if s in EVALUATED for t in ts for p in parts(t)}
)


def relabel(job: tuple[str, int, bool]) -> dict[str, Any]:
    """One scene's label now and (if asked) whether Fast Downward's translator agrees."""
    split, index, fd = job
    g = split_scene(split, index)
    now = label(g.scene)
    agrees = fd_agrees(g.scene, g.achievable) if fd else None
    return {"split": split, "index": index, "template": g.template, "file": g.achievable,
            "file_length": g.plan_length, "now": now.achievable, "now_length": now.plan_length,
            "fd_agrees": agrees}  # fmt: skip


def moved(c: dict[str, Any]) -> bool:
    """Whether a relabelled scene's label or plan length differs from the file's."""
    return (c["now"], c["now_length"]) != (c["file"], c["file_length"])


def split_row(split: str) -> dict[str, Any]:
    entry = _seed_table()[split]
    n = len(split_seeds(split))
    good: Counter[str] = Counter()
    for i in range(n):
        g = split_scene(split, i)
        good.update(set(parts(g.template)) if g.achievable else ())
    lengths = [p for a, p in zip(entry["achievable"], entry["plan_length"], strict=True) if a]
    bad = n - sum(entry["achievable"])
    return {"split": split, "scenes": n, "unachievable": bad, "share": bad / n,
            "plan_median": statistics.median(lengths), "plan_min": min(lengths),
            "plan_max": max(lengths), "achievable_per_template": dict(sorted(good.items())),
            "relaxed_after_seed": entry.get("template_quota_relaxed_after_seed"),
            "only_templates": entry.get("only_templates", []),
            "only_templates_after_seed": entry.get("only_templates_after_seed"),
            "fd_checked_at_selection": entry["labels_checked_with_fd_translator"],
            "sha256": entry["sha256"]}  # fmt: skip


def issue_lines(
    rows: list[dict[str, Any]], checks: list[dict[str, Any]], fd: bool
) -> list[tuple[str, bool, str]]:
    """(line, met, what was measured) for each of the issue's lines."""
    by = {r["split"]: r for r in rows}
    out = []
    sizes = [f"{s} {r['scenes']}" for s, r in by.items()]
    ok = all(r["scenes"] >= MIN_SCENES.get(s, 100) for s, r in by.items())
    out.append(("each split >= 100 scenes (train >= 400)", ok, ", ".join(sizes)))
    shares = [f"{s} {r['share']:.0%}" for s, r in by.items()]
    ok = all((r["unachievable"] == 0 and r["plan_min"] >= HARD_MIN_ACTIONS) if s == "hard"
             else SHARE[0] <= r["share"] <= SHARE[1] for s, r in by.items())  # fmt: skip
    hard = f"hard: shortest plan {by['hard']['plan_min']}" if "hard" in by else "no hard split"
    out.append(("5-15 % unachievable (hard none, every plan >= 12 actions)", ok,
                ", ".join(shares) + f"; {hard}"))  # fmt: skip
    tests: Counter[str] = Counter()
    for s, r in by.items():
        if s in EVALUATED:
            tests.update(r["achievable_per_template"])
    low = {t: tests[t] for t in TEMPLATES_TESTED if tests[t] < MIN_PER_TEMPLATE}
    fewest = min(TEMPLATES_TESTED, key=lambda t: tests[t])
    out.append(
        (
            "every template >= 20 achievable scenes across the test splits and hard",
            not low,
            f"fewest: {fewest} {tests[fewest]}" + (f"; below: {low}" if low else ""),
        )
    )
    train = {p for t in SPLIT_TEMPLATES["train"] for p in parts(t)}
    absent = sorted({p for t in SPLIT_TEMPLATES["test-tasks"] for p in parts(t)} - train)
    out.append(("test-tasks holds >= 2 templates absent from train", len(absent) >= 2,
                ", ".join(absent)))  # fmt: skip
    differ = [c for c in checks if moved(c)]
    out.append(
        ("every label is the planner's now", not differ, f"{len(differ)} of {len(checks)} differ")
    )
    if fd:
        no = [c for c in checks if c["fd_agrees"] is not True]
        out.append(("every label agrees with Fast Downward's translator", not no,
                    f"{len(checks) - len(no)} of {len(checks)} agree"))  # fmt: skip
    return out


def to_markdown(rows: list[dict[str, Any]], lines: list[tuple[str, bool, str]],
                checks: list[dict[str, Any]]) -> str:  # fmt: skip
    templates = sorted({t for r in rows for t in r["achievable_per_template"]})
    out = [
        "<!-- written by benchmarks/v2_splits.py from assets/procedural/procedural-v2.toml -->",
        "",
        "| split | scenes | unachievable | plan length (median, min-max) | quota relaxed after "
        "seed | sha256 |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        relaxed = "–" if r["relaxed_after_seed"] is None else str(r["relaxed_after_seed"])
        if r.get("only_templates"):
            relaxed += (
                f"; only {', '.join(r['only_templates'])} after {r['only_templates_after_seed']}"
            )
        out.append(f"| {r['split']} | {r['scenes']} | {r['unachievable']} ({r['share']:.0%}) | "
                   f"{r['plan_median']:g} ({r['plan_min']}-{r['plan_max']}) | {relaxed} | "
                   f"`{r['sha256'][:12]}` |")  # fmt: skip
    out += ["", "Achievable scenes per template (a composition counts for each of its parts):",
            "", "| template | " + " | ".join(r["split"] for r in rows) + " |",
            "|---|" + "---|" * len(rows)]  # fmt: skip
    for t in templates:
        cells = [str(r["achievable_per_template"].get(t, "–")) for r in rows]
        out.append(f"| {t} | " + " | ".join(cells) + " |")
    out += ["", "Issue #38's lines on this file:", "", "| line | met | measured |", "|---|---|---|"]
    out += [f"| {line} | {'yes' if ok else '**no**'} | {what} |" for line, ok, what in lines]
    differ = [c for c in checks if moved(c) or c["fd_agrees"] is False]
    if differ:
        out += ["", "Labels that differ (file -> planner now; Fast Downward's translator):", ""]
        out += [f"* `procedural-v2/{c['split']}/{c['index']:04d}` ({c['template']}): "
                f"{c['file']} ({c['file_length']}) -> {c['now']} ({c['now_length']}); "
                f"FD agrees with the file: {c['fd_agrees']}" for c in differ]  # fmt: skip
    return "\n".join(out) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-fd", action="store_true", help="skip Fast Downward's translator")
    ap.add_argument("--results", default="docs/results")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    splits = available_splits()
    jobs = [(s, i, not args.no_fd) for s in splits for i in range(len(split_seeds(s)))]
    with ProcessPoolExecutor(args.workers) as pool:
        checks = list(pool.map(relabel, jobs, chunksize=8))
    rows = [split_row(s) for s in splits]
    lines = issue_lines(rows, checks, not args.no_fd)
    data = {"args": vars(args), "splits": rows,
            "issue_lines": [{"line": a, "met": b, "measured": c} for a, b, c in lines],
            "differ": [c for c in checks if moved(c) or c["fd_agrees"] is False]}  # fmt: skip
    text = to_markdown(rows, lines, checks)
    write_results(args.results, "procedural_splits_v2", data, text, indent=1)
    print(text)


if __name__ == "__main__":
    main()
