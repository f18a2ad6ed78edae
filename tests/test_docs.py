"""The documentation covers the program and agrees with it (no Sphinx build: `make docs` is that).

The pages generated from the code (`docs/_scripts`) are produced in process, the hand-written
pages are read as text: every ``utamp`` subcommand and option, every env option and every
``info`` key of every registered id must appear in them; figures stated in more than one place
(action-space sizes, suite scene counts, the README's results table) must equal what the code
and the result files say; every module, file and command a page names must exist.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import re
import sys
from functools import cache
from pathlib import Path

import gymnasium as gym
import jinja2
import pytest

import utamp_gym
from utamp_gym.env.options import EnvOptions
from utamp_gym.env.registry import env_definitions, env_ids
from utamp_gym.methods.perceivers import ENTRY_POINT_GROUP

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS / "_scripts"))

import cli_reference  # noqa: E402
import env_pages  # noqa: E402
import facts  # noqa: E402

README_MAX_LINES = 200
#: a path in the repository that a page names
PATH = r"\b((?:benchmarks|tests|examples|assets|envs|utamp_gym)/[\w/.-]+\.(?:py|toml|pddl))"


def written_pages() -> dict[str, str]:
    """The hand-written sources: README.md and docs/*.md (result fragments included)."""
    pages = {"README.md": (ROOT / "README.md").read_text()}
    for path in sorted(DOCS.glob("*.md")) + sorted((DOCS / "results").glob("*.md")):
        pages[str(path.relative_to(ROOT))] = path.read_text()
    return pages


@cache
def env_page(env_id: str) -> tuple[env_pages.EnvFacts, str]:
    measured = env_pages.measure(env_id)
    return measured, env_pages.page(measured)


@cache
def cli_text() -> str:
    return cli_reference.reference()


def _subcommands(
    parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
) -> list[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    """Walked here, not with the generator's own walk, so a command it misses fails."""
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += [((*path, name), sub), *_subcommands(sub, (*path, name))]
    return found


def _section(text: str, path: tuple[str, ...]) -> str:
    """The part of the CLI reference under the heading of ``utamp PATH``."""
    head = re.search(rf"^#+ `utamp {' '.join(path)}`$", text, re.M)
    assert head, f"no section for `utamp {' '.join(path)}` in the CLI reference"
    following = re.compile(r"^\(cli-utamp-[\w-]+\)=$", re.M).search(text, head.end())
    return text[head.end() : following.start() if following else len(text)]


# ------------------------------------------------------------------ coverage
def test_every_subcommand_and_option_is_in_the_cli_reference() -> None:
    from utamp_gym.cli import build_parser

    text = cli_text()
    commands = _subcommands(build_parser())
    assert {p for p, _ in commands} >= {("eval", "merge"), ("scenes", "list"), ("scenes", "show")}
    for path, parser in commands:
        section = _section(text, path)
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
                continue
            names = action.option_strings or [cli_reference._positional_name(action)]
            for name in names:
                row = re.search(rf"^\|[^\n]*`{re.escape(name)}`[^\n]*\|$", section, re.M)
                assert row, f"`utamp {' '.join(path)}` option {name} is not documented"
                help_cell = row.group(0).rstrip("|").rsplit("|", 1)[-1].strip()
                assert help_cell, f"`utamp {' '.join(path)} {name}` has no help text"
    for name in ("utamp plan --json", "utamp run --json", "utamp run --closed-loop --json"):
        assert f"`{name}` prints one JSON object with the keys" in text


def test_cli_json_keys_are_what_the_commands_print(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from utamp_gym.cli import main

    assert main(["plan", "kitchen-demo", "--json"]) == 0
    printed = list(json.loads(capsys.readouterr().out))
    assert cli_reference.json_keys()["utamp plan --json"] == printed


@pytest.mark.parametrize("env_id", env_ids())
def test_every_env_option_is_documented(env_id: str) -> None:
    measured, page = env_page(env_id)
    options = {p.name for p in measured.parameters}
    assert options, f"{env_id}: no keyword options found"
    definition = next(d for d in env_definitions() if d.id == env_id)
    if definition.entry_point == "utamp_gym.env.kitchen:UTampKitchenEnv":
        assert options == {f.name for f in dataclasses.fields(EnvOptions)}
    described = measured.sections.get("Options", "")
    for name in sorted(options):
        assert re.search(rf"^\| `{name}` \|", page, re.M), f"{env_id}: option {name} not listed"
        assert re.search(rf"``[^`]*\b{name}\b[^`]*``", described), (
            f"{env_id}: option {name} is not described in the **Options** section of "
            f"{definition.entry_point}'s docstring"
        )


@pytest.mark.parametrize("env_id", env_ids())
def test_every_info_key_is_documented(env_id: str) -> None:
    env = gym.make(env_id, grounding="symbolic")
    _, info_reset = env.reset(seed=0)
    mask = env.unwrapped.action_masks()
    *_, info_step = env.step(int(mask.nonzero()[0][0]))
    env.close()
    measured, page = env_page(env_id)
    # and the keys of a whole episode (some are set on its last step only)
    keys = set(info_reset) | set(info_step) | set(measured.info_keys)
    described = measured.sections.get("Info", "")
    for key in sorted(keys):
        assert re.search(rf"^\| `{key}` \|", page, re.M), f"{env_id}: info key {key} not listed"
        assert f"``{key}``" in described, (
            f"{env_id}: info key {key!r} is not described in the **Info** section of "
            f"{measured.entry_point}'s docstring"
        )


@pytest.mark.parametrize("env_id", env_ids())
def test_env_page_reports_the_spaces_gym_make_builds(env_id: str) -> None:
    page = env_page(env_id)[1]
    env = gym.make(env_id, grounding="symbolic")
    assert f"`{env.action_space}`" in page
    for key, space in env.observation_space.spaces.items():
        assert f"| `{key}` | `{env_pages.space_text(space)}` |" in page
    env.close()


def test_readme_is_short() -> None:
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines"


# ------------------------------------------------------------------ consistency
def _without_fences(text: str) -> str:
    return re.sub(r"^(`{3,})[^\n]*\n.*?^\1\s*$", "", text, flags=re.M | re.S)


def _prose(text: str) -> str:
    """`text` without code blocks and inline code (MyST substitutes only in prose)."""
    return re.sub(r"`[^`\n]*`", "", _without_fences(text))


@cache
def action_sizes() -> set[int]:
    sizes = set()
    for env_id in env_ids():
        sizes |= set(env_page(env_id)[0].n_actions_by_masks.values())
    return sizes


def test_action_space_sizes_agree_with_the_envs() -> None:
    sizes = action_sizes()
    pattern = r"\b(\d{1,3}(?:,\d{3})*|\d+) (?:macro )?(?:actions|logits)\b|Discrete\((\d+)\)"
    for name, text in written_pages().items():
        for m in re.finditer(pattern, text):
            n = int((m.group(1) or m.group(2)).replace(",", ""))
            if n >= 100:  # smaller counts are steps or episodes, not action spaces
                assert n in sizes, f"{name}: {m.group(0)!r}, but the envs have {sorted(sizes)}"


def test_suite_scene_counts_agree_with_the_suites() -> None:
    counts = {s: c["kept"] for s, c in facts.suite_counts().items()}
    for name, text in written_pages().items():
        # whole-suite claims ("all 106 pick-place scenes", "pick-place (106)"); a count of
        # some of a suite's scenes ("17 sliding scenes failed") is not one
        for m in re.finditer(r"\ball (\d+) (pick-place|sliding|extra) scenes\b", text):
            assert int(m.group(1)) == counts[m.group(2)], f"{name}: {m.group(0)!r} ({counts})"
        for m in re.finditer(r"\b(pick-place|sliding|extra) \((\d+)\)", text):
            assert int(m.group(2)) == counts[m.group(1)], f"{name}: {m.group(0)!r} ({counts})"
    env_counts = {d.id: d.kwargs.get("suite") for d in env_definitions()}
    for env_id, suite in env_counts.items():
        if suite is not None:
            assert f"| scenes | {counts[suite]} (" in env_page(env_id)[1]


def test_readme_results_table_is_the_one_the_result_files_give() -> None:
    rows = facts.paper_rows(DOCS / "results")
    readme = (ROOT / "README.md").read_text()
    assert "\n".join(rows) in readme, "README.md's results table differs from docs/results"


def test_substitutions_used_by_the_pages_exist() -> None:
    import json

    measured = [env_page(i)[0] for i in env_ids()]
    known = facts.facts(measured)
    known["results"] = {  # as docs/conf.py loads them
        p.stem.replace("-", "_"): json.loads(p.read_text())
        for p in (DOCS / "results").glob("*.json")
    }
    render = jinja2.Environment(undefined=jinja2.StrictUndefined)  # as MyST renders them
    for name, text in written_pages().items():
        if name != "docs/writing-docs.md":  # which shows the syntax in code on purpose
            for span in re.findall(r"`[^`\n]*`", _without_fences(text)):
                assert "{{" not in span, f"{name}: {span} is not substituted inside code"
        for expression in re.findall(r"\{\{.*?\}\}", _prose(text)):
            try:
                render.from_string(expression).render(known)
            except jinja2.UndefinedError as exc:
                raise AssertionError(f"{name}: {expression}: {exc}") from None


def test_names_the_pages_mention_exist() -> None:
    """Dotted ``utamp_gym.x.y`` names import, repository paths exist."""
    for name, text in written_pages().items():
        for ref in sorted(set(re.findall(r"\butamp_gym(?:\.[A-Za-z_]\w*)+", text))):
            if ref == ENTRY_POINT_GROUP:  # the perceivers' entry-point group, not a module
                continue
            parts = ref.split(".")
            for split in range(len(parts), 0, -1):
                try:
                    obj = importlib.import_module(".".join(parts[:split]))
                except ModuleNotFoundError:
                    continue
                for attr in parts[split:]:
                    assert hasattr(obj, attr), f"{name}: {ref} does not exist"
                    obj = getattr(obj, attr)
                break
        for path in sorted(set(re.findall(PATH, text))):
            assert (ROOT / path).exists(), f"{name}: {path} does not exist"


def test_utamp_commands_in_the_pages_use_real_options() -> None:
    from utamp_gym.cli import build_parser

    parsers = {" ".join(p): sub for p, sub in _subcommands(build_parser())}
    command = re.compile(
        r"\butamp ((?:scenes (?:list|show))|(?:eval merge)|plan|run|view|validate|eval|train)"
        r"\b([^`\n]*)"
    )
    for name, text in written_pages().items():
        for m in command.finditer(text):
            parser = parsers[m.group(1)]
            valid = {s for a in parser._actions for s in a.option_strings}
            for flag in re.findall(r"(?<![\w-])(--[a-z][a-z-]*)", m.group(2)):
                assert flag in valid, f"{name}: `utamp {m.group(1)}` has no option {flag}"


def test_docs_extra_and_make_target_exist() -> None:
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    docs_extra = " ".join(project["optional-dependencies"]["docs"])
    for package in ("sphinx", "furo", "myst-parser"):
        assert package in docs_extra
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r"^docs: ", makefile, re.M) and "sphinx -W" in makefile
    assert "make docs" in (ROOT / ".ci" / "run").read_text()
    assert utamp_gym.__name__ == "utamp_gym"
