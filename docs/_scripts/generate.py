"""Write every generated documentation file (run by `make docs` before Sphinx).

    python docs/_scripts/generate.py [--no-pictures]

Writes (all git-ignored; the pages are rebuilt from the code on every build):

* ``docs/envs/index.md`` and ``docs/envs/<id>.md`` (+ PNG pictures): one page per env id of
  `utamp_gym.env.registry.env_ids()` (`env_pages`);
* ``docs/_generated/cli.md``: the ``utamp`` reference from the argparse parsers (`cli_reference`);
* ``docs/_generated/cameras.md``: the RGB-D cameras of `utamp_gym.sim.cameras` (`cameras`);
* ``docs/_generated/explain.md``: what ``utamp plan FILE --explain`` prints for the unsolvable
  scene files of ``tests/scenes`` (`explain_example`);
* ``docs/_generated/suites.md``, ``dependencies.md``: the suite statistics and the
  requirements of ``pyproject.toml`` (`facts`);
* ``docs/_generated/facts.json``: the figures pages quote as ``{{ name }}`` (`facts`).

Nothing sets a rendering backend here: the physics pictures use what ``render_mode="rgb_array"``
picks in this environment.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import cameras  # noqa: E402
import cli_reference  # noqa: E402
import env_pages  # noqa: E402
import explain_example  # noqa: E402
import facts as facts_module  # noqa: E402

DOCS = HERE.parent
GENERATED = DOCS / "_generated"
ENVS = DOCS / "envs"


def _write(path: Path, text: str) -> None:
    """Write only when the text changed (Sphinx then rebuilds only what changed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--no-pictures", action="store_true", help="skip the rendered pictures (faster)"
    )
    args = ap.parse_args(argv)
    from utamp_gym.env.registry import env_ids

    start = time.perf_counter()
    measured = []
    for env_id in env_ids():
        f = env_pages.measure(env_id, pictures=None if args.no_pictures else ENVS)
        _write(ENVS / f"{env_id}.md", env_pages.page(f))
        measured.append(f)
    known = {f"{f.env_id}.md" for f in measured} | {"index.md"}
    for stale in ENVS.glob("*.md"):  # an id that was removed loses its page
        if stale.name not in known:
            stale.unlink()
    _write(ENVS / "index.md", env_pages.index(measured))
    # autosummary writes one page per module under _generated/api and never removes one: a
    # module that moved or went away would leave a page that fails to import
    shutil.rmtree(GENERATED / "api", ignore_errors=True)
    _write(GENERATED / "cli.md", cli_reference.reference())
    _write(GENERATED / "cameras.md", cameras.cameras_table())
    _write(GENERATED / "explain.md", explain_example.example())
    _write(GENERATED / "suites.md", facts_module.suites_table())
    _write(GENERATED / "paper_table.md", facts_module.paper_table(DOCS / "results"))
    _write(
        GENERATED / "dependencies.md",
        facts_module.dependencies_table(DOCS.parent / "pyproject.toml"),
    )
    _write(
        GENERATED / "facts.json",
        json.dumps(facts_module.facts(measured), indent=1, sort_keys=True) + "\n",
    )
    print(
        f"generated {len(measured)} env page(s), the CLI reference and the facts in "
        f"{time.perf_counter() - start:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
