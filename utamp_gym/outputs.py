"""Output paths of the `utamp` commands, checked before any work starts.

Why: a sweep or a training run that has computed for an hour must not end in a traceback
because ``--out`` names a file, lies under one, or is read-only. Each command checks its output
paths first (`output_dir`, `output_file`); a bad one raises `OutputPathError`, which the CLI
prints as one line naming the path (exit code 2).
"""

from __future__ import annotations

from pathlib import Path

from utamp_gym.errors import UtampError


class OutputPathError(UtampError, OSError):
    """An output path that cannot be written; the message names the option and the path."""


def output_dir(path: str | Path, option: str) -> Path:
    """`path` as a directory to write into: created (with its parents) if missing, else an
    `OutputPathError` saying why not (a file in the way, no permission, a read-only place)."""
    return _writable_dir(Path(path), Path(path), f"{option} {path}")


def output_file(path: str | Path, option: str) -> Path:
    """`path` as a file to (over)write: its directory created if missing; an
    `OutputPathError` if the path is a directory or its directory cannot be written."""
    p = Path(path)
    what = f"{option} {path}"
    if p.is_dir():
        raise OutputPathError(f"{what}: is a directory; give a file name")
    _writable_dir(p.parent, p, what)
    return p


def new_output_dir(path: str | Path, option: str) -> Path:
    """`path` as a directory that a library creates itself (LeRobot refuses an existing
    one): it must not exist yet, and its parent is created if missing and probed."""
    p = Path(path)
    what = f"{option} {path}"
    if p.exists():
        raise OutputPathError(f"{what}: already exists; give a new folder")
    _writable_dir(p.parent, p, what)
    return p


def _writable_dir(p: Path, named: Path, what: str) -> Path:
    """`p` made and probed with a temporary file; `named` is the path the user gave."""
    blocker = next((a for a in (p, *p.parents) if a.exists() and not a.is_dir()), None)
    if blocker is not None:
        where = "is a file" if blocker == named else f"lies under {blocker}, which is a file"
        raise OutputPathError(f"{what}: {where}, not a directory")
    # here, not at the top: `utamp plan` loads this module on every run, --out or not, and
    # tempfile brings shutil, lzma, bz2 and random
    import tempfile

    try:
        p.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=p):
            pass
    except OSError as exc:
        reason = exc.strerror or str(exc)
        raise OutputPathError(f"{what}: cannot write there ({reason})") from None
    return p
