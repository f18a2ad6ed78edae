"""`utamp plan` / `utamp run` / `utamp eval` on every procedural-v2 split: the default
method follows the scene's labelling domain (the extended utamp2x), the paper's scenes keep
utamp2-gt (issue #38)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from utamp_gym.cli import main
from utamp_gym.cli.common import PAPER_METHOD, default_method
from utamp_gym.suites.procedural_v2 import available_splits, split_scene, split_scenes
from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD

SPLITS = available_splits()


def test_default_method_by_scene() -> None:
    assert LABEL_METHOD == "utamp2x-rules" and PAPER_METHOD == "utamp2-gt"
    assert default_method("procedural-v2/test-tasks/0003") == LABEL_METHOD
    for name in ("pick-place/000", "sliding/003", "procedural-v1/train/0000", "kitchen-demo"):
        assert default_method(name) == PAPER_METHOD


@pytest.mark.parametrize("split", SPLITS)
def test_plan_defaults_to_the_label_method_and_agrees_with_the_label(split, capsys) -> None:
    # the first achievable and (where the split has one) the first unachievable scene
    scenes = split_scenes(split)
    picks = [next(i for i, s in enumerate(scenes) if s.achievable)]
    picks += [i for i, s in enumerate(scenes) if not s.achievable][:1]
    for i in picks:
        name = f"procedural-v2/{split}/{i:04d}"
        assert main(["plan", name, "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        assert data["method"] == LABEL_METHOD and data["scene"] == name
        assert data["solved"] == split_scene(split, i).achievable, name


def test_plan_keeps_utamp2_gt_on_the_papers_scenes(capsys) -> None:
    assert main(["plan", "pick-place/000"]) == 0
    assert "[utamp2-gt]" in capsys.readouterr().out.splitlines()[0]


def test_run_names_the_scenes_goal(capsys) -> None:
    name = "procedural-v2/test-tasks/0000"
    assert main(["run", name]) == 0
    out = capsys.readouterr()
    lines = out.out.splitlines()
    assert lines[0] == f"{name} [{LABEL_METHOD}, seed 0]: success", lines
    template = split_scene("test-tasks", 0).template
    assert lines[2].startswith(f"  goal ({template}): ") and "tower on" not in out.out
    assert out.err == ""


@pytest.mark.slow
@pytest.mark.parametrize("split", SPLITS)
def test_run_every_split(split, capsys) -> None:
    i = next(i for i, s in enumerate(split_scenes(split)) if s.achievable)
    assert main(["run", f"procedural-v2/{split}/{i:04d}", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["method"] == LABEL_METHOD and data["success"] is True


@pytest.mark.parametrize("split", SPLITS)
def test_eval_defaults_to_the_label_method(split, tmp_path: Path, capsys) -> None:
    out = tmp_path / split
    argv = ["eval", "--suite", f"procedural-v2/{split}", "--limit", "2", "--workers", "0"]
    assert main([*argv, "--grounding", "symbolic", "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [r["method"] for r in rows] == [LABEL_METHOD] * 2
    for r in rows:  # the split file's label is what the planner finds
        index = int(r["scene"].rpartition("/")[2])
        assert (r["solved"] == "true") == split_scene(split, index).achievable, r["scene"]
    assert capsys.readouterr().err == ""


def test_scenes_list_json_is_one_document_and_jsonl_one_record_a_line(capsys) -> None:
    """`--json` parses as one JSON document (a list, as `utamp plan --json` prints one
    object); `--jsonl` holds the same records, one per line; both together are refused."""
    suite = "procedural-v2/test-tasks"
    assert main(["scenes", "list", "--suite", suite, "--json"]) == 0
    records = json.loads(capsys.readouterr().out)
    scenes = split_scenes("test-tasks")
    assert isinstance(records, list) and len(records) == len(scenes)
    for r, s in zip(records, scenes, strict=True):
        assert r["name"] == s.scene.name and r["template"] == s.template
        assert r["achievable"] is s.achievable and r["instruction"]
    assert main(["scenes", "list", "--suite", suite, "--jsonl"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [json.loads(line) for line in lines] == records
    with pytest.raises(SystemExit) as exit_:
        main(["scenes", "list", "--suite", suite, "--json", "--jsonl"])
    assert exit_.value.code == 2
    assert "not allowed with argument --json" in capsys.readouterr().err
