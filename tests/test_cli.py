"""The `utamp` command line: exact names, JSON fields, files and exit codes."""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest
import wide
from procs import downward_children, process_alive, user_env

from utamp_gym.cli import build_parser, main
from utamp_gym.deadline import Deadline
from utamp_gym.errors import PlanningTimeout
from utamp_gym.planning import fast_downward
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene import scene_from_dict
from utamp_gym.suites import ALL_SUITES, GOAL_SUITES, packaged_scene_names, suite_scenes
from utamp_gym.suites.procedural_v2 import available_splits


def test_scenes_list_and_show(capsys) -> None:
    assert main(["scenes", "list", "--suite", "sliding"]) == 0
    names = capsys.readouterr().out.split()
    assert names[0] == "sliding/000" and len(names) == 42
    assert main(["scenes", "show", "pick-place/017"]) == 0
    scene = scene_from_dict(tomllib.loads(capsys.readouterr().out))
    assert scene.name == "pick-place/017"


def test_scenes_list_names_every_packaged_scene_and_every_suite_scene(capsys) -> None:
    assert main(["scenes", "list"]) == 0
    names = capsys.readouterr().out.split()
    generated = [s for s in GOAL_SUITES if s.rpartition("/")[2] in available_splits()]
    assert generated and set(generated) <= set(ALL_SUITES)  # procedural-v2: generated splits
    suites = [s for s in ALL_SUITES if s not in GOAL_SUITES or s in generated]
    expected = [*packaged_scene_names(), *(s.name for x in suites for s in suite_scenes(x))]
    assert names == expected and "kitchen-demo" in names
    for name in names[:2]:  # each listed name is one `utamp scenes show` accepts
        assert main(["scenes", "show", name]) == 0
        assert scene_from_dict(tomllib.loads(capsys.readouterr().out)).name == name


def test_plan_json_and_out_dir(capsys, tmp_path: Path) -> None:
    assert main(["plan", "kitchen-demo", "--json", "--out", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in (
        "scene",
        "method",
        "n_objects",
        "solved",
        "plan",
        "plan_length",
        "planning_time_s",
        "reason",
    ):
        assert key in data
    assert data["solved"] and data["plan_length"] == len(data["plan"]) > 0
    assert data["plan"][0].startswith("(pick-support ")
    plan_lines = (tmp_path / "plan.txt").read_text().splitlines()
    assert plan_lines == data["plan"]
    args = [str(tmp_path / f) for f in ("domain.pddl", "problem.pddl", "plan.txt")]
    assert main(["validate", *args]) == 0
    (tmp_path / "bad.txt").write_text("\n".join(reversed(plan_lines)) + "\n")
    assert main(["validate", args[0], args[1], str(tmp_path / "bad.txt")]) == 1
    err = capsys.readouterr().err
    assert "step 1" in err and "precondition" in err


def test_a_perceived_plan_says_how_it_planned_what_was_in_doubt(capsys) -> None:
    # train/0056: the plate's well read too narrow for the food box; the wider reading hopes
    assert main(["plan", "procedural-v1/train/0056", "--method", "utamp2-perceived"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1] == "  (likely values unsolvable, planned hoping (sizes))"
    assert out[2].startswith("  (pick-support ")
    assert main(["plan", "procedural-v1/train/0056", "--method", "utamp2-perceived", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] and data["doubt"] == "likely values unsolvable, planned hoping (sizes)"
    assert main(["plan", "kitchen-demo", "--json"]) == 0
    assert "doubt" not in json.loads(capsys.readouterr().out)


def test_plan_unsolvable_scene_exits_zero(capsys, tmp_path: Path, demo_dict) -> None:
    import tomli_w

    demo_dict["objects"] = [o for o in demo_dict["objects"] if o["name"] in ("tray", "pan", "mug")]
    demo_dict["objects"][2]["orientation"] = "upright"
    path = tmp_path / "hard.toml"
    path.write_text(tomli_w.dumps(demo_dict))
    assert main(["plan", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] is False and data["reason"]


def test_bad_input_exits_two_with_a_message(capsys, tmp_path: Path) -> None:
    assert main(["plan", "pick-place/999"]) == 2
    assert "unknown scene 'pick-place/999'; did you mean" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[workspace]\nmin = [0, 0]\n')
    assert main(["plan", str(bad)]) == 2
    assert f"{bad}: field 'workspace.min'" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "-inf", "1e9", "86400.5", "soon"])
def test_invalid_timeout_exits_two_with_one_line(capsys, value: str) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["plan", "kitchen-demo", "--timeout", value])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("utamp plan: error: argument --timeout: ")


def test_timeout_bounds_the_whole_plan_command(capsys, monkeypatch: pytest.MonkeyPatch) -> None:
    """The limit counts from the command's start, parsing and imports included: the deadline
    the planner gets began before `main` parsed anything. (Checked on the deadline itself, not
    with a stopwatch: machines are shared and noisy.)"""
    from utamp_gym.cli import plan as plan_cli

    calls: list[tuple[Deadline, float]] = []

    def spy(*args: object, **kwargs: object) -> object:
        calls.append((kwargs["deadline"], time.perf_counter()))  # type: ignore[arg-type]
        return plan_scene(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(plan_cli, "plan_scene", spy)  # the planner the command calls
    before = time.perf_counter()
    assert main(["plan", "kitchen-demo", "--timeout", "7", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["solved"]
    ((deadline, called),) = calls
    assert deadline.limit == 7 and before <= deadline.at - 7 <= called
    # a limit used up before planning starts is reported as a time-out (exit 0), not a plan
    assert (
        main(["plan", "pick-place/105", "--method", "utamp1", "--timeout", "1e-6", "--json"]) == 0
    )
    data = json.loads(capsys.readouterr().out)
    assert data["timed_out"] is True and data["solved"] is False and data["plan"] == []
    assert data["phase"] == "scene" and "1e-06 s" in data["reason"]


def test_grounding_watches_the_deadline() -> None:
    """In-process grounding stops at the deadline: this task's grounding takes minutes by
    construction (`tests/wide.py`); with a 0.2 s limit the call ends in grounding, at once."""
    start = time.perf_counter()
    with pytest.raises(PlanningTimeout) as info:
        fast_downward.solve(wide.DOMAIN, wide.problem(), timeout=0.2)
    wall = time.perf_counter() - start
    assert info.value.phase == "grounding" and "0.2 s" in str(info.value)
    assert wall < 20, wall  # minutes without the checks; generous for a loaded machine


def test_sigint_during_search_exits_130_and_kills_the_search() -> None:
    # UTAMP-1 with LM-cut on five objects: seconds of grounding, then a search of about a second
    cmd = [sys.executable, "-m", "utamp_gym.cli", "plan", "pick-place/105", "--method", "utamp1"]
    cmd += ["--search", "astar-lmcut", "--json"]
    proc = subprocess.Popen(
        cmd,
        env=user_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # a background job of a non-interactive shell starts with SIGINT ignored; undo that
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        limit = time.monotonic() + 120
        children: list[int] = []
        while not children and proc.poll() is None and time.monotonic() < limit:
            children = downward_children(proc.pid)
            time.sleep(0.005)
        assert children, "the search never started (or finished before it could be seen)"
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 130 and out == ""
    assert err == "utamp: interrupted\n"
    deadline = time.monotonic() + 2.0
    while any(map(process_alive, children)) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not any(map(process_alive, children))


def test_plan_imports_no_gym_torch_mujoco_or_numpy(tmp_path: Path) -> None:
    cmd = [sys.executable, "-X", "importtime", "-m", "utamp_gym.cli", "plan", "pick-place/017"]
    run = subprocess.run(
        [*cmd, "--json"], env=user_env(), capture_output=True, text=True, check=True
    )
    assert json.loads(run.stdout)["solved"]
    imported = {ln.split("|")[-1].strip() for ln in run.stderr.splitlines() if "|" in ln}
    assert "utamp_gym.planning.state_planner" in imported  # the check sees our imports
    heavy = ("gymnasium", "torch", "mujoco", "pinocchio", "ompl", "matplotlib", "numpy")
    assert not {m for m in imported if m.split(".")[0] in heavy}
    # nor the dataclasses machinery (it imports inspect, and each class execs its methods)
    assert not imported & {"dataclasses", "inspect"}
    # nor tempfile (shutil, lzma, bz2, random): only an --out probe needs it
    assert not imported & {"tempfile", "shutil"}
    # nor Fast Downward's own translator (`fast_downward.solve` only) nor the goal templates
    # (a scene file's goal given by template only)
    off_path = {"utamp_gym.planning.fast_downward", "utamp_gym.planning.fd_translate"}
    assert not imported & (off_path | {"utamp_gym.tasks.templates", "utamp_gym.tasks.attributes"})


def test_help_lists_every_subcommand_and_each_subcommand_help_is_complete(capsys) -> None:
    """`utamp CMD` builds only CMD's parser; the top-level help still names them all."""
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for name in ("scenes", "plan", "run", "view", "validate", "eval", "train"):
        assert f"    {name} " in out, name
    expected = {
        "plan": ("--method", "--timeout", "--search", "--noise", "--out", "--explain"),
        "run": ("--video", "--pose-noise", "--disturbance", "--closed-loop"),
        "eval": ("--suite", "--methods", "--executor", "--pose-noise", "--closed-loop"),
        "validate": ("domain", "problem", "plan"),
    }
    for command, options in expected.items():
        with pytest.raises(SystemExit) as exc:
            main([command, "--help"])
        assert exc.value.code == 0
        out = capsys.readouterr().out
        assert out.startswith(f"usage: utamp {command}"), out
        assert all(option in out for option in options), (command, out)


def test_only_the_utamp_process_freezes_its_objects_before_exit(capsys) -> None:
    """`main()` as the process (no argv) hands its objects to no more garbage collections
    (the process ends next); `main(argv)` in a longer-lived process leaves the collector be."""
    import gc

    frozen = gc.get_freeze_count()
    assert main(["scenes", "list", "--suite", "sliding"]) == 0
    assert gc.get_freeze_count() == frozen
    code = (
        "import gc, sys; sys.argv = ['utamp', 'scenes', 'list', '--suite', 'sliding']; "
        "from utamp_gym.cli import main; rc = main(); print(rc, gc.get_freeze_count() > 0)"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], env=user_env(), capture_output=True, text=True, check=True
    )
    assert run.stdout.splitlines()[-1] == "0 True"


def test_only_a_light_utamp_process_turns_the_garbage_collector_off() -> None:
    """`utamp plan` (a light command, as the process) runs without cyclic collections;
    `main(argv)` in a longer-lived process and the heavy commands leave the collector on."""
    import gc

    assert main(["scenes", "list", "--suite", "sliding"]) == 0
    assert gc.isenabled()
    code = (
        "import gc, sys; sys.argv = ['utamp', *sys.argv[1:]]; "
        "import utamp_gym.cli as cli; seen = []; "
        "run = cli._run; cli._run = lambda *a, **k: seen.append(gc.isenabled()) or run(*a, **k); "
        "import atexit; atexit.register(lambda: print(seen, gc.isenabled(), file=sys.stderr)); "
        "sys.exit(cli.main())"
    )
    for argv, enabled in ((["plan", "pick-place/017", "--json"], False),
                          (["run", "--help"], True)):  # fmt: skip
        run = subprocess.run(
            [sys.executable, "-c", code, *argv], env=user_env(), capture_output=True, text=True
        )
        assert run.returncode == 0, run.stderr
        assert run.stderr.splitlines()[-1] == f"[True] {enabled}", (argv, run.stderr)


# ---------------------------------------------------------------- unwritable output paths
OUTPUTS = {
    "plan --out": ["plan", "kitchen-demo", "--out", "{path}"],
    "run --video": ["run", "pick-place/080", "--video", "{path}"],
    "eval --out": ["eval", "--suite", "pick-place", "--limit", "1", "--workers", "0", "--out",
                   "{path}"],
    "eval merge OUT": ["eval", "merge", "{path}", "{existing}"],
    "train --out": ["train", "--steps", "64", "--no-progress", "--out", "{path}"],
    "demos --out": ["demos", "--suite", "pick-place", "--episodes", "1", "--out", "{path}"],
    "demos export-lerobot --out": ["demos", "export-lerobot", "--root", "{existing}",
                                   "--dataset", "utamp/x-v0", "--out", "{path}"],
}  # fmt: skip


def _read_only(tmp_path: Path) -> Path:
    """A directory nobody can write into: a mode-555 folder, or for root (who ignores modes)
    sysfs, where even root cannot make a folder."""
    if os.geteuid() == 0:
        return Path("/sys")
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    return folder


@pytest.mark.parametrize("kind", ["under a file", "a file or folder", "read-only"])
@pytest.mark.parametrize("command", OUTPUTS, ids=OUTPUTS.keys())
def test_unwritable_output_paths_exit_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str, kind: str
) -> None:
    """Checked before any work: one line on stderr naming the path, exit code 2."""
    afile = tmp_path / "notes.txt"
    afile.write_text("not a folder\n")
    video = command == "run --video"
    path = {
        "under a file": afile / ("run.mp4" if video else "out"),
        "a file or folder": tmp_path if video else afile,  # a video needs a file name
        "read-only": _read_only(tmp_path) / "utamp-out" / ("run.mp4" if video else "x"),
    }[kind]
    args = [a.format(path=path, existing=tmp_path) for a in OUTPUTS[command]]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("utamp: error: ") and str(path) in err, err
    assert afile.read_text() == "not a folder\n"


def test_every_output_option_of_every_subcommand_is_tested() -> None:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    found = set()
    for name, subparser in sub.choices.items():
        for action in subparser._actions:
            found |= {f"{name} {o}" for o in action.option_strings if o in ("--out", "--video")}
    assert found and found <= set(OUTPUTS), found - set(OUTPUTS)


def test_every_utamp_command_named_in_help_docs_and_sources_exists() -> None:
    """``utamp X`` in a help text, a page, a docstring or a comment is a subcommand."""
    from utamp_gym.cli import SUBCOMMANDS

    root = Path(__file__).resolve().parents[1]
    texts = {
        str(p.relative_to(root)): p.read_text()
        for pattern in ("*.md", "docs/**/*.md", "utamp_gym/**/*.py", "examples/*.py",
                        "benchmarks/*.py", "docs/_scripts/*.py", "Makefile")
        for p in root.glob(pattern)
        if "_generated" not in p.parts
    }  # fmt: skip
    parsers = [build_parser()]
    while parsers:  # every parser's usage, description and option help, nested ones too
        parser = parsers.pop()
        texts[parser.prog] = parser.format_help()
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                parsers += action.choices.values()
    names = {name for name, _, _ in SUBCOMMANDS}
    named = {
        (where, command)
        for where, text in texts.items()
        for command in re.findall(r"\butamp ([a-z][a-z-]*)", text)
    }
    assert {c for _, c in named} >= {"plan", "train", "demos"}  # the search finds them
    assert not {(w, c) for w, c in named if c not in names}
