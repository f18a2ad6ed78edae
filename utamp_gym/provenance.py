"""Where a results file came from: the commit of the code and the exact command that wrote it.

Every file in ``docs/results/`` records both, so a figure can be traced to the code that
measured it and re-made with the same command. A JSON result carries them as its first keys
(``"commit"``, ``"command"``); a Markdown result ends with a footer line (`footer`), which
`parse_footer` reads back; a PNG plot keeps them as text chunks (`png_metadata`, read back by
`read_png`). `write_json` and `write_markdown` add them; ``utamp eval``'s summary
writer (`utamp_gym.eval.summary.write_summary`) and the scripts in ``benchmarks/`` use them.

The commit is ``git rev-parse --short HEAD`` of the checkout the package was imported from,
with ``-dirty`` when tracked files differ from it (``unknown`` outside a git checkout). The
command is ``sys.argv`` as one shell line: ``utamp ...`` for the command line, ``python
benchmarks/x.py ...`` (a path relative to the repository) for a script.
"""

from __future__ import annotations

import functools
import json
import re
import shlex
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

#: the checkout this package lives in (the repository root of a source install)
ROOT = Path(__file__).resolve().parents[1]
#: the Markdown footer: ``_Written by `CMD` at commit `SHA`._`` (an optional note after it)
FOOTER = re.compile(
    r"^_Written by `(?P<command>[^`]+)` at commit `(?P<commit>[^`]+)`(?P<note>.*)\._$"
)


@functools.cache
def commit(root: Path = ROOT) -> str:
    """The short commit of `root`'s checkout, ``-dirty`` if tracked files changed (files
    under ``docs/results/`` aside: a run that writes them leaves the code as it was).

    Fixed by the first call in a process (the code it runs was imported by then): a long run
    calls it at its start, so that editing the checkout meanwhile does not change it."""
    try:
        sha = _git(root, "rev-parse", "--short", "HEAD").strip()
        # results being written (one run after another in one checkout) are not the code
        dirty = _git(
            root, "status", "--porcelain", "--untracked-files=no", "--", ".", ":!docs/results"
        ).strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return f"{sha}-dirty" if dirty else sha


def _git(root: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(root), *args], capture_output=True, text=True, check=True, timeout=30
    ).stdout


def command(argv: Sequence[str] | None = None) -> str:
    """`argv` (default ``sys.argv``) as the shell line that re-runs it from the repository."""
    argv = list(sys.argv if argv is None else argv)
    if not argv or argv[0] == "-c":
        return shlex.join(["python", *argv])
    prog = Path(argv[0])
    if prog.name == "utamp" or (prog.parent.name == "cli" and prog.name == "__main__.py"):
        head = ["utamp"]
    else:
        try:
            rel = prog.resolve().relative_to(ROOT)
        except ValueError:
            rel = prog
        head = ["python", str(rel)] if prog.suffix == ".py" else [str(rel)]
    return shlex.join([*head, *argv[1:]])


def provenance(argv: Sequence[str] | None = None) -> dict[str, str]:
    """``{"commit": ..., "command": ...}`` of this process."""
    return {"commit": commit(), "command": command(argv)}


def stamped(data: dict[str, Any], prov: dict[str, str] | None = None) -> dict[str, Any]:
    """`data` with the provenance as its first keys (one already in `data` is kept)."""
    prov = provenance() if prov is None else prov
    return {**prov, **data}


def footer(prov: dict[str, str]) -> str:
    """The Markdown footer line of `prov` (its ``note``, if any, in brackets)."""
    note = f" ({prov['note']})" if prov.get("note") else ""
    return f"_Written by `{prov['command']}` at commit `{prov['commit']}`{note}._"


def parse_footer(text: str) -> dict[str, str] | None:
    """The provenance of a Markdown result (its last non-empty line), or None."""
    lines = [line for line in text.splitlines() if line.strip()]
    m = FOOTER.match(lines[-1]) if lines else None
    if m is None:
        return None
    out = {"command": m.group("command"), "commit": m.group("commit")}
    note = m.group("note").strip()
    if note.startswith("(") and note.endswith(")"):
        out["note"] = note[1:-1]
    return out


def with_footer(text: str, prov: dict[str, str] | None = None) -> str:
    """Markdown `text` ending with the provenance footer (replacing an old one)."""
    prov = provenance() if prov is None else prov
    lines = text.rstrip("\n").splitlines()
    if lines and FOOTER.match(lines[-1]):
        lines = lines[:-1]
        while lines and not lines[-1].strip():
            lines.pop()
    return "\n".join([*lines, "", footer(prov)]) + "\n"


def write_json(
    path: str | Path, data: dict[str, Any], *, indent: int | None = 2, **kw: Any
) -> dict[str, str]:
    """Write `data` as JSON to `path`, stamped with this process's provenance (or the one
    `data` carries already, e.g. a table re-written from its own JSON); returns it."""
    data = stamped(data)
    Path(path).write_text(json.dumps(data, indent=indent, **kw) + "\n")
    return {k: data[k] for k in ("commit", "command", "note") if k in data}


def write_markdown(path: str | Path, text: str, prov: dict[str, str] | None = None) -> None:
    """Write Markdown `text` to `path`, ending with the footer of `prov` (default: this
    process's provenance)."""
    Path(path).write_text(with_footer(text, prov))


def png_metadata(prov: dict[str, Any] | None = None) -> dict[str, str]:
    """The provenance as PNG text chunks (``savefig(..., metadata=png_metadata())``);
    `prov` may be any mapping holding ``commit`` and ``command`` (e.g. a summary)."""
    prov = provenance() if prov is None else prov
    keys = ("commit", "command", "note")
    return {k: str(prov[k]) for k in keys if prov.get(k)}


def read_png(path: str | Path) -> dict[str, str] | None:
    """The provenance text chunks of a PNG (`png_metadata`), or None without them."""
    from PIL import Image  # matplotlib's own dependency

    with Image.open(path) as image:
        text = dict(getattr(image, "text", {}))
    if "commit" not in text or "command" not in text:
        return None
    return {k: text[k] for k in ("commit", "command", "note") if k in text}
