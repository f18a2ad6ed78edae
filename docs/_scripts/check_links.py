"""Check every local link of the built HTML site (run by `make docs` after Sphinx).

    python docs/_scripts/check_links.py [build/docs/html]

Resolves each ``href`` and ``src`` of every ``.html`` file under the site that points into
the site (no scheme, no ``//host``; ``mailto:`` and friends are skipped): the file must
exist, and a ``#fragment`` into an HTML page must name an ``id`` (or ``<a name>``) of that
page. Exits 1 listing every broken link (``page: target``), 0 printing nothing otherwise.
Sphinx's ``linkcheck`` builder checks remote links; this one needs no network.
"""

from __future__ import annotations

import argparse
import sys
from functools import cache
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

DEFAULT_SITE = Path(__file__).resolve().parents[2] / "build" / "docs" / "html"


class _Page(HTMLParser):
    """The links (``href``/``src``) and anchors (``id``, ``<a name>``) of one page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.links: list[str] = []
        self.anchors: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for key, value in attrs:
            if value is None:
                continue
            if key in ("href", "src"):
                self.links.append(value)
            elif key == "id" or (key == "name" and tag == "a"):
                self.anchors.add(value)


@cache
def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


def _local_target(link: str) -> tuple[str, str] | None:
    """(path, fragment) of a link into the site; None for remote or non-file links."""
    parts = urlsplit(link)
    if parts.scheme or parts.netloc or link.startswith("//"):
        return None
    return unquote(parts.path), unquote(parts.fragment)


def broken_links(site: Path) -> list[str]:
    """``page: link`` for every local link of the site that does not resolve."""
    site = site.resolve()
    broken = []
    for page_path in sorted(site.rglob("*.html")):
        for link in _parse(page_path).links:
            target = _local_target(link)
            if target is None:
                continue
            path, fragment = target
            dest = (page_path.parent / path).resolve() if path else page_path
            if dest.is_dir():
                dest = dest / "index.html"
            where = page_path.relative_to(site)
            if not dest.is_file():
                broken.append(f"{where}: {link}")
            elif fragment and dest.suffix == ".html" and fragment not in _parse(dest).anchors:
                broken.append(f"{where}: {link} (no id '{fragment}' in {dest.name})")
    return broken


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("site", nargs="?", type=Path, default=DEFAULT_SITE, help="built HTML")
    args = parser.parse_args(argv)
    if not args.site.is_dir():
        print(f"check_links: {args.site} is not a directory (build it first)", file=sys.stderr)
        return 2
    broken = broken_links(args.site)
    if broken:
        print(f"{len(broken)} broken local link(s) in {args.site}:", file=sys.stderr)
        for line in broken:
            print(f"  {line}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
