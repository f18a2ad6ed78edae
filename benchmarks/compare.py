"""What the benchmarks share (one module instead of a private copy in each script).

* measuring this tree against an earlier commit (`physics_speed.py`, `planning_speed.py`,
  `train_speed.py`): `git` in this repository, the earlier commit checked out as a detached
  worktree for one run (`base_worktree`), and a `Worker` process running one tree's code;
* summaries: `med` (the median, NaN when empty), `rounded` (4 significant digits),
  `cpu_s` (CPU time of this process and its reaped children) and `load` (the load
  averages: the machine is shared, times are indicative). Intervals are the package's
  (`utamp_gym.eval.intervals`: Wilson, bootstrap, Student t).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

ROOT = Path(__file__).resolve().parents[1]


def git(*args: str) -> str:
    """Run git in this repository; its output, stripped."""
    return subprocess.run(
        ["git", "-C", str(ROOT), *args], check=True, capture_output=True, text=True
    ).stdout.strip()


@contextlib.contextmanager
def base_worktree(commit: str, prefix: str) -> Iterator[Path]:
    """`commit` checked out as a detached worktree ``base`` in a temporary folder (whose
    other files the run may use), removed with the folder when the run ends."""
    with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        tree = Path(tmp) / "base"
        git("worktree", "add", "--detach", str(tree), commit)
        try:
            yield tree
        finally:
            git("worktree", "remove", "--force", str(tree))


class Worker:
    """A worker process running `script` (``python script *args``) with one tree's code.

    It answers one JSON line per request: the first line it prints says which package it
    imported (``{"ready": path}``), checked to lie inside `tree`. `env` adds environment
    variables (e.g. ``OMP_NUM_THREADS``)."""

    def __init__(
        self,
        label: str,
        tree: Path,
        script: Path,
        *args: str,
        env: Mapping[str, str] | None = None,
    ):
        self.label, self.tree = label, tree
        variables = dict(os.environ, PYTHONPATH=str(tree), **(env or {}))
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(script).resolve()), *args],
            cwd=tree,
            env=variables,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        ready = json.loads(self._read())
        if not Path(ready["ready"]).resolve().is_relative_to(tree.resolve()):
            raise RuntimeError(f"{label}: imported {ready['ready']}, not from {tree}")

    def _read(self) -> str:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"worker '{self.label}' ({self.tree}) exited")
        return line

    def ask(self, **req: Any) -> dict[str, Any]:
        """Send one request (a JSON line); its answer."""
        stdin: IO[str] | None = self.proc.stdin
        assert stdin is not None
        stdin.write(json.dumps(req) + "\n")
        stdin.flush()
        return json.loads(self._read())

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


def med(xs: Iterable[float]) -> float:
    """The median of `xs` (NaN when empty)."""
    xs = list(xs)
    return statistics.median(xs) if xs else float("nan")


def cpu_s() -> float:
    """CPU seconds of this process and its reaped children (workers, planner processes)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def load() -> list[float]:
    """The 1, 5 and 15 minute load averages, rounded to 0.01."""
    return [round(x, 2) for x in os.getloadavg()]


def rounded(x: Any) -> Any:
    """`x` with every float to 4 significant digits (a smaller JSON file)."""
    if isinstance(x, float):
        return float(f"{x:.4g}")
    if isinstance(x, dict):
        return {k: rounded(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [rounded(v) for v in x]
    return x
