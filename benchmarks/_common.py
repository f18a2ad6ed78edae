"""What the benchmark scripts share: writing a results page (its JSON and its Markdown) and
finishing a success-rate figure.

A benchmark's `main` ends the same way in each: the folder made, ``<name>.json`` written with
the run's data stamped with its provenance (`utamp_gym.provenance.write_json`), and
``<name>.md`` with the page's text and that provenance as its footer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from utamp_gym.provenance import png_metadata, write_json, write_markdown


def write_results(
    folder: str | Path, name: str, data: dict[str, Any], text: str, **json_options: Any
) -> None:
    """Write ``folder/<name>.json`` (`data`, with `json_options` such as ``indent``) and
    ``folder/<name>.md`` (`text` with the provenance footer), making `folder` first."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    prov = write_json(folder / f"{name}.json", data, **json_options)
    write_markdown(folder / f"{name}.md", text, prov)


def save_success_plot(fig: Any, ax: Any, path: str | Path, title: str) -> None:
    """Finish a plot of success rates (y from 0 to 1, the title, a legend) and save it to
    `path` with the provenance in its PNG metadata; the figure is closed."""
    import matplotlib.pyplot as plt  # matplotlib: only when a figure is written

    ax.set_ylabel("success rate")
    ax.set_ylim(0, 1.02)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120, metadata=png_metadata())
    plt.close(fig)
