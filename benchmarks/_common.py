"""What the benchmark scripts share: writing a results page (its JSON and its Markdown).

A benchmark's `main` ends the same way in each: the folder made, ``<name>.json`` written with
the run's data stamped with its provenance (`utamp_gym.provenance.write_json`), and
``<name>.md`` with the page's text and that provenance as its footer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from utamp_gym.provenance import write_json, write_markdown


def write_results(
    folder: str | Path, name: str, data: dict[str, Any], text: str, **json_options: Any
) -> None:
    """Write ``folder/<name>.json`` (`data`, with `json_options` such as ``indent``) and
    ``folder/<name>.md`` (`text` with the provenance footer), making `folder` first."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    prov = write_json(folder / f"{name}.json", data, **json_options)
    write_markdown(folder / f"{name}.md", text, prov)
