"""What the benchmarks that measure this tree against an earlier commit share: git in this
repository, and the earlier commit checked out as a detached worktree for one run
(`physics_speed.py`, `planning_speed.py`, `train_speed.py`)."""

from __future__ import annotations

import contextlib
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

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
