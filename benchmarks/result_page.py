"""The tail the grasp benchmarks share (`grasp_coverage.py`, `edge_slide.py`,
`edge_reach.py`): shares in their tables and the page written from a run's data."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from utamp_gym.provenance import write_json, write_markdown


def share(k: int, n: int) -> str:
    """``k/n (p%)``, or a dash for none."""
    return f"{k}/{n} ({k / n:.0%})" if n else "–"


def write_page(
    out: str | Path, data: dict[str, Any], markdown: Callable[[dict[str, Any]], str], start: float
) -> None:
    """Record the run's wall time (since `start`, a `time.perf_counter` reading) in `data` and
    write ``<out>.json`` and ``<out>.md`` (`markdown` of the data, with the provenance footer)."""
    data["wall_s"] = round(time.perf_counter() - start, 1)
    out = Path(out)
    prov = write_json(out.with_suffix(".json"), data, indent=1)
    write_markdown(out.with_suffix(".md"), markdown(data), prov)
