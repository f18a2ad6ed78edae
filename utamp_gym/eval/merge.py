"""`utamp eval merge OUT DIR...`: join the output folders of a split sweep into one.

Shards (`--shard`), seed ranges (`--seed-offset`) and scene subsets (`--scenes`) run on
several machines each leave a folder with its own ``results.csv``. Merging keeps each run
once: a run present in two folders must have the same outcome in both (every column
but the wall-clock times), otherwise the merge stops and names the run, the differing
columns and both folders. OUT gets ``results.csv``, ``summary.md/json`` and the plots.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from utamp_gym.errors import UtampError
from utamp_gym.eval.records import Key, ResultRow, key_text, read_rows, write_rows
from utamp_gym.eval.summary import summarize, write_summary


class MergeConflictError(UtampError):
    """Two folders hold the same run with different outcomes."""


@dataclass(frozen=True)
class Merged:
    """The merged rows and where each one came from."""

    rows: list[ResultRow]
    sources: list[Path]
    duplicates: int  # runs found in more than one folder (with equal outcomes)


def merge_rows(dirs: Sequence[str | Path]) -> Merged:
    """The rows of every ``DIR/results.csv``, each run once; conflicting duplicates raise."""
    sources: list[Path] = []
    for d in dirs:
        path = Path(d)
        if path.resolve() not in {s.resolve() for s in sources}:
            sources.append(path)
    seen: dict[Key, tuple[ResultRow, Path]] = {}
    duplicates = 0
    for folder in sources:
        csv_path = folder / "results.csv"
        if not csv_path.is_file():
            raise UtampError(f"{folder}: no results.csv (not a `utamp eval` output folder)")
        for row in read_rows(csv_path):
            if row.key not in seen:
                seen[row.key] = (row, folder)
                continue
            first, where = seen[row.key]
            diff = first.differences(row)
            if diff:
                shown = "; ".join(
                    f"{c}: {first.to_csv()[c]!r} vs {row.to_csv()[c]!r}" for c in diff[:4]
                )
                raise MergeConflictError(
                    f"conflicting rows for run ({key_text(row.key)}) in {where} and {folder}: "
                    f"{shown}"
                )
            duplicates += 1
    rows = [row for row, _ in seen.values()]
    if not rows:
        raise UtampError("nothing to merge: the results.csv files hold no rows")
    return Merged(rows, sources, duplicates)


def _only(values: set[str], what: str) -> str:
    if len(values) != 1:
        raise UtampError(
            f"cannot merge rows of several {what}s ({', '.join(sorted(values))}): "
            f"merge each {what} into its own folder"
        )
    return next(iter(values))


def merged_context(merged: Merged) -> dict[str, Any]:
    """The summary context of merged rows (from the rows and the folders' summary.json)."""
    rows = merged.rows
    parts: list[dict[str, Any]] = []
    for folder in merged.sources:
        try:
            parts.append(json.loads((folder / "summary.json").read_text()))
        except (OSError, ValueError):
            continue  # a folder without a summary (e.g. an interrupted sweep)
    methods: list[str] = []
    notes: list[str] = []
    for p in parts:
        methods += [m for m in p.get("methods_requested", []) if m not in methods]
        notes += [n for n in p.get("notes", []) if n not in notes]
    for m in dict.fromkeys(r.method for r in rows):
        if m not in methods:
            methods.append(m)
    seeds = sorted({r.seed for r in rows})
    timeouts = sorted({p["planner_timeout_s"] for p in parts if "planner_timeout_s" in p})
    return {
        "suite": _only({r.suite for r in rows}, "suite"),
        "grounding": _only({r.grounding for r in rows}, "grounding"),
        "methods_requested": methods,
        "seeds": len(seeds),
        "seed_offset": seeds[0],
        "scene_pattern": None,
        "shard": None,
        "scenes": len({r.scene for r in rows}),
        "noise_levels": sorted({r.noise for r in rows if r.noise is not None}),
        "planner_timeout_s": timeouts[0] if len(timeouts) == 1 else timeouts or None,
        "notes": notes,
        "wall_time_s": None,  # the parts ran apart: no one wall time
        "resumed_rows": None,
        "merged_from": [str(s) for s in merged.sources],
        "duplicate_rows": merged.duplicates,
    }


def merge_outputs(out: str | Path, dirs: Sequence[str | Path]) -> dict[str, Any]:
    """Merge `dirs` into `out`: results.csv, summary.md/json and plots; returns the summary.

    `out` may be one of `dirs`; a results.csv already in `out` that is not listed is
    refused rather than silently overwritten or mixed in.
    """
    # lazy: utamp_gym.eval.plots imports matplotlib
    from utamp_gym.eval.plots import write_plots

    out = Path(out)
    if not dirs:
        raise UtampError("utamp eval merge: name at least one folder to merge")
    listed = {Path(d).resolve() for d in dirs}
    if (out / "results.csv").exists() and out.resolve() not in listed:
        raise UtampError(
            f"{out} already holds a results.csv: list {out} among the folders to merge "
            "its rows too, or merge into a new folder"
        )
    merged = merge_rows(dirs)
    context = merged_context(merged)
    out.mkdir(parents=True, exist_ok=True)
    write_rows(out / "results.csv", merged.rows)
    summary = summarize(read_rows(out / "results.csv"), context=context)
    write_summary(out, summary)
    write_plots(out, summary)
    return summary
