"""Shared parts of the sweeps of ``utamp eval`` over a suite's splits.

`procedural_sweep.py` (procedural-v1) and `v2_physics.py` (procedural-v2) both run, per split,
``utamp eval --out OUT/<split>`` (or, with ``--summarize-only``, read what an earlier run
left there) and summarize that split's results.csv rows: `sweep_parser` is their options,
`sweep_splits` that loop, `reason_kind` and `by_count` how they group failure reasons.
"""

from __future__ import annotations

import argparse
import csv
import re
import subprocess
import sys
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

Rows = list[dict[str, str]]


def sweep_parser(
    description: str, *, seeds: int, splits: list[str] | tuple[str, ...], out: str
) -> argparse.ArgumentParser:
    """The options of a sweep of `utamp eval` over a suite's splits, with their defaults."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--seeds", type=int, default=seeds)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--splits", default=",".join(splits))
    ap.add_argument("--out", default=out)
    ap.add_argument("--results", default="docs/results")
    ap.add_argument("--summarize-only", action="store_true", help="read OUT, run nothing")
    return ap


def sweep_splits(
    args: argparse.Namespace,
    eval_command: Callable[[str, argparse.Namespace], list[str]],
    summarize: Callable[[str, Rows], dict[str, Any]],
) -> list[dict[str, Any]]:
    """Per split of ``args.splits`` (comma-separated), in order: run ``utamp
    <eval_command(split, args)>`` unless ``args.summarize_only`` (the command writes
    OUT/<split>; ``utamp eval`` resumes from a results.csv already there), then
    ``summarize(split, rows)`` of OUT/<split>/results.csv."""
    summaries = []
    for split in (s.strip() for s in args.splits.split(",")):
        if not split:
            continue
        if not args.summarize_only:
            command = eval_command(split, args)
            print("utamp " + " ".join(command), flush=True)
            subprocess.run([sys.executable, "-m", "utamp_gym.cli", *command], check=True)
        with (Path(args.out) / split / "results.csv").open(newline="") as f:
            rows = list(csv.DictReader(f))
        summaries.append(summarize(split, rows))
    return summaries


def reason_kind(reason: str) -> str:
    """A failure reason without its step, action, names and numbers: its kind."""
    text = reason.split("): ", 1)[-1]  # drop "step N (action)"
    text = re.sub(r"\bobj\d\b|(?<!robot's )\bbase\b", "X", text)
    text = re.sub(r"\s*\(.*\)", "", text)  # details such as the contacts or the IK's notes
    return re.sub(r"-?\d+(\.\d+)?", "#", text).strip()


def by_count(kinds: list[Counter[str]]) -> list[str]:
    """The failure kinds counted in `kinds` (one counter a split), the most frequent over all
    splits first, ties by name (a set's order would change with the run's hash seed)."""
    return sorted({k for c in kinds for k in c}, key=lambda k: (-sum(c[k] for c in kinds), k))
