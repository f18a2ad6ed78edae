"""Copy a ``utamp eval`` output folder's summaries (and plots) into ``docs/results/``.

    python docs/_scripts/publish_eval.py OUT NAME [--plots [PLOT,...]] [--results docs/results]

``OUT/summary.json`` and ``summary.md`` become ``NAME-summary.json`` and ``NAME-summary.md``;
with ``--plots``, each plot of ``OUT`` (or the ones named) becomes ``NAME-<plot>.png``. The
files are copied as ``utamp eval`` wrote them, so they keep the commit and the command it
recorded in them (`utamp_gym.provenance`); a summary without them is refused. For example::

    utamp eval --suite pick-place --grounding physics --pose-noise 0.002 --out out/pp
    python docs/_scripts/publish_eval.py out/pp pick-place-physics --plots
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parents[1] / "results"
PLOTS = ("success_by_objects.png", "planning_time_by_objects.png", "success_vs_f1.png")


def publish(
    out: Path, name: str, *, plots: tuple[str, ...] = (), results: Path = RESULTS
) -> list[Path]:
    """Copy the summaries and `plots` of `out` to `results` as ``NAME-...``; the copies."""
    summary = json.loads((out / "summary.json").read_text())
    if "commit" not in summary or "command" not in summary:
        raise SystemExit(f"{out}/summary.json records no commit and command: run utamp eval again")
    pairs = [(out / f"summary{ext}", results / f"{name}-summary{ext}") for ext in (".json", ".md")]
    for p in plots:
        if not (out / p).is_file():
            raise SystemExit(f"{out}/{p}: no such plot (utamp eval writes {', '.join(PLOTS)})")
        pairs.append((out / p, results / f"{name}-{p}"))
    for src, dst in pairs:
        shutil.copyfile(src, dst)
    return [dst for _, dst in pairs]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="a utamp eval --out folder")
    ap.add_argument("name", help="the prefix in docs/results, e.g. pick-place-physics")
    ap.add_argument(
        "--plots",
        nargs="?",
        const="",
        help="also copy these plots (comma-separated; none named: every plot OUT has)",
    )
    ap.add_argument("--results", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    if args.plots is None:
        plots: tuple[str, ...] = ()
    elif args.plots:
        plots = tuple(args.plots.split(","))
    else:
        plots = tuple(p for p in PLOTS if (args.out / p).is_file())
    for path in publish(args.out, args.name, plots=plots, results=args.results):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
