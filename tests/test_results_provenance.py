"""Every results file records where it came from, and the README's results are generated.

Each file in ``docs/results/`` (JSON, Markdown, PNG) records the commit and the exact command
that wrote it (`utamp_gym.provenance`); the command must still parse with today's command line
(``utamp ...``: `utamp_gym.cli.build_parser`; ``python benchmarks/x.py ...``: the script's
``build_parser()``), so removing or renaming an option that a results file was made with
fails here. The README's results blocks must be what ``docs/_scripts/readme.py`` writes from
those files.
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from utamp_gym import provenance
from utamp_gym.cli import build_parser
from utamp_gym.eval.plots import write_plots
from utamp_gym.eval.summary import write_summary

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

FILES = sorted(p.name for p in RESULTS.iterdir() if p.suffix in (".json", ".md", ".png"))
COMMIT = re.compile(r"[0-9a-f]{7,40}(-dirty)?")


def recorded(path: Path) -> dict[str, str] | None:
    """The provenance a results file records, by its kind."""
    if path.suffix == ".json":
        data = json.loads(path.read_text())
        return {k: data[k] for k in ("commit", "command") if k in data} or None
    if path.suffix == ".md":
        return provenance.parse_footer(path.read_text())
    return provenance.read_png(path)


def command_error(command: str) -> str | None:
    """Why `command` does not parse with the current code (None: it does)."""
    argv = shlex.split(command)
    if argv[0] == "utamp":
        parser, args = build_parser(argv[1] if len(argv) > 1 else None), argv[1:]
    elif argv[0] == "python" and len(argv) > 1 and argv[1].endswith(".py"):
        if not (ROOT / argv[1]).is_file():
            return f"{argv[1]} does not exist"
        script = readme.load_script(argv[1])
        if not hasattr(script, "build_parser"):
            return f"{argv[1]} has no build_parser()"
        parser, args = script.build_parser(), argv[2:]
    else:
        return f"not a utamp command or a repository script: {command!r}"
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            parser.parse_args(args)
        except SystemExit:
            return err.getvalue().strip().splitlines()[-1] if err.getvalue() else "exited"
    return None


def _git_knows(commit: str) -> bool | None:
    sha = commit.removesuffix("-dirty")
    try:
        done = subprocess.run(
            ["git", "-C", str(ROOT), "cat-file", "-e", f"{sha}^{{commit}}"],
            capture_output=True,
            check=False,
        )
    except OSError:
        return None
    return done.returncode == 0


@pytest.mark.parametrize("name", FILES)
def test_results_file_records_its_commit_and_a_command_the_code_still_takes(name: str) -> None:
    prov = recorded(RESULTS / name)
    assert prov is not None, f"docs/results/{name} records no commit and command"
    assert COMMIT.fullmatch(prov["commit"]), f"docs/results/{name}: commit {prov['commit']!r}"
    if (ROOT / ".git").exists():
        assert _git_knows(prov["commit"]), f"docs/results/{name}: no commit {prov['commit']}"
    error = command_error(prov["command"])
    assert error is None, f"docs/results/{name}: `{prov['command']}` no longer parses: {error}"


def test_the_command_check_fails_on_an_option_that_does_not_exist() -> None:
    ok = "utamp eval --suite pick-place --grounding physics --pose-noise 0.002 --out out/x"
    assert command_error(ok) is None
    assert "--no-such" in (command_error(ok + " --no-such") or "")
    assert command_error("python benchmarks/memory.py --resets 10") is None
    assert "--no-such" in (command_error("python benchmarks/memory.py --no-such 1") or "")
    assert "does not exist" in (command_error("python benchmarks/gone.py") or "")
    assert command_error("make bench") is not None


def test_readme_results_blocks_are_what_the_results_files_give() -> None:
    text = (ROOT / "README.md").read_text()
    assert readme.rewrite(text, readme.blocks()) == text, (
        "README.md's results differ from docs/results: run python docs/_scripts/readme.py"
    )


def test_readme_states_the_pose_noise_its_paper_table_was_measured_with() -> None:
    summaries = [json.loads((RESULTS / f"{s}-physics-summary.json").read_text())
                 for s in ("pick-place", "sliding")]  # fmt: skip
    noise = {s["pose_noise_m"] for s in summaries}
    assert len(noise) == 1
    paper = readme.blocks()["paper"]
    (m,) = noise
    assert (f"{m * 1000:g} mm noise" if m else "exact object poses") in paper
    for s in summaries:
        assert s["command"] in paper and s["commit"] in paper


def test_readme_rewrite_replaces_only_the_marked_blocks() -> None:
    text = "a\n<!-- results:x begin (generated) -->\nold\n<!-- results:x end -->\nb\n"
    assert readme.rewrite(text, {"x": "new\n"}) == text.replace("old\n", "\nnew\n\n")
    with pytest.raises(ValueError, match="no markers"):
        readme.rewrite("a\n", {"x": "new\n"})


def test_a_summary_records_the_process_that_wrote_it(tmp_path: Path) -> None:
    summary = {"suite": "pick-place", "grounding": "physics", "runs": 0, "methods": [],
               "noise_sweep": []}  # fmt: skip
    write_summary(tmp_path, summary)
    stored = json.loads((tmp_path / "summary.json").read_text())
    assert stored["command"] == provenance.command() and stored["commit"] == provenance.commit()
    footer = provenance.parse_footer((tmp_path / "summary.md").read_text())
    assert footer == {"command": stored["command"], "commit": stored["commit"]}
    summary["methods"] = [_method()]
    for path in write_plots(tmp_path, summary):
        assert provenance.read_png(path) == footer, path.name


def _method() -> dict[str, object]:
    stats = {"runs": 2, "successes": 1, "success_rate": 0.5, "success_rate_ci95": [0.1, 0.9],
             "planning_time_mean_s": 0.1, "planning_time_std_s": 0.01,
             "planning_time_ci95_s": [0.09, 0.11]}  # fmt: skip
    return {"label": "utamp2-gt", "method": "utamp2-gt", "noise": None, **stats,
            "by_objects": {"2": stats}}  # fmt: skip


def test_command_is_the_line_that_reruns_it() -> None:
    utamp = str(Path(sys.executable).parent / "utamp")
    assert provenance.command([utamp, "eval", "--out", "a b"]) == "utamp eval --out 'a b'"
    script = str(ROOT / "benchmarks" / "memory.py")
    assert provenance.command([script, "--resets", "5"]) == (
        "python benchmarks/memory.py --resets 5"
    )


def test_footer_and_json_keep_a_provenance_they_are_given(tmp_path: Path) -> None:
    old = {"commit": "abc1234", "command": "python benchmarks/memory.py", "note": "from history"}
    text = provenance.with_footer("# t\n\nbody\n", old)
    assert provenance.parse_footer(text) == old
    assert provenance.with_footer(text, old) == text  # an old footer is replaced, not stacked
    prov = provenance.write_json(tmp_path / "a.json", {**old, "x": 1})
    assert prov == old and json.loads((tmp_path / "a.json").read_text())["commit"] == "abc1234"
    prov = provenance.write_json(tmp_path / "b.json", {"x": 1})
    assert prov == provenance.provenance()


def test_publish_copies_a_sweep_with_its_provenance_and_refuses_one_without(
    tmp_path: Path,
) -> None:
    import publish_eval

    out, results = tmp_path / "out", tmp_path / "results"
    out.mkdir()
    results.mkdir()
    summary = {"suite": "pick-place", "grounding": "symbolic", "runs": 0, "methods": [],
               "noise_sweep": []}  # fmt: skip
    (out / "summary.json").write_text(json.dumps(summary))
    (out / "summary.md").write_text("# t\n")
    with pytest.raises(SystemExit, match="records no commit"):
        publish_eval.publish(out, "x", results=results)
    write_summary(out, summary)
    copies = publish_eval.publish(out, "x", results=results)
    assert sorted(p.name for p in copies) == ["x-summary.json", "x-summary.md"]
    assert recorded(results / "x-summary.md") == recorded(results / "x-summary.json")
    with pytest.raises(SystemExit, match="no such plot"):
        publish_eval.publish(out, "x", plots=("success_vs_f1.png",), results=results)


def test_a_checkout_is_dirty_for_changed_code_not_for_results_being_written(
    tmp_path: Path,
) -> None:
    def git(*args: str) -> None:
        subprocess.run(["git", "-C", str(tmp_path), *args], check=True, capture_output=True)

    (tmp_path / "docs" / "results").mkdir(parents=True)
    (tmp_path / "code.py").write_text("x = 1\n")
    (tmp_path / "docs" / "results" / "speed.md").write_text("| a |\n")
    git("init", "-q")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "one")
    (tmp_path / "docs" / "results" / "speed.md").write_text("| b |\n")  # a run's output
    clean = provenance.commit.__wrapped__(tmp_path)
    assert re.fullmatch(r"[0-9a-f]{7,40}", clean), clean
    (tmp_path / "code.py").write_text("x = 2\n")
    assert provenance.commit.__wrapped__(tmp_path) == f"{clean}-dirty"
