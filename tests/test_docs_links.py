"""docs/_scripts/check_links.py, the local link check `make docs` runs on the built site."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_scripts"))

import check_links


def page(body: str) -> str:
    return f"<!doctype html><html><body>{body}</body></html>"


def test_every_kind_of_broken_local_link_is_reported(tmp_path: Path, capsys) -> None:
    (tmp_path / "api").mkdir()
    (tmp_path / "_static").mkdir()
    (tmp_path / "_static" / "style.css").write_text("")
    (tmp_path / "api" / "index.html").write_text(page('<h1 id="top">API</h1>'))
    (tmp_path / "index.html").write_text(
        page(
            '<link href="_static/style.css?v=1"><a href="api/">dir</a>'
            '<a href="api/index.html#top">ok</a><a href="#here" id="here">self</a>'
            '<a href="https://example.org/missing.html">remote</a><a href="mailto:a@b">mail</a>'
            '<a href="builtins.html">missing</a><img src="img/x.png">'
            '<a href="api/index.html#nowhere">fragment</a><a href="#gone">own fragment</a>'
        )
    )
    assert check_links.broken_links(tmp_path) == [
        "index.html: builtins.html",
        "index.html: img/x.png",
        "index.html: api/index.html#nowhere (no id 'nowhere' in index.html)",
        "index.html: #gone (no id 'gone' in index.html)",
    ]
    assert check_links.main([str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("4 broken local link(s)") and "  index.html: builtins.html" in err


def test_a_sound_site_passes_silently(tmp_path: Path, capsys) -> None:
    (tmp_path / "index.html").write_text(page('<a href="index.html">home</a>'))
    assert check_links.main([str(tmp_path)]) == 0
    assert capsys.readouterr() == ("", "")
    assert check_links.main([str(tmp_path / "absent")]) == 2
