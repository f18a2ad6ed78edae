"""The `utamp` command line: exact names, JSON fields, files and exit codes."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from utamp_gym.cli import main
from utamp_gym.scene import scene_from_dict


def test_scenes_list_and_show(capsys) -> None:
    assert main(["scenes", "list", "--suite", "sliding"]) == 0
    names = capsys.readouterr().out.split()
    assert names[0] == "sliding/000" and len(names) == 42
    assert main(["scenes", "show", "pick-place/017"]) == 0
    scene = scene_from_dict(tomllib.loads(capsys.readouterr().out))
    assert scene.name == "pick-place/017"


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
    assert "unknown scene 'pick-place/999'; valid:" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[workspace]\nmin = [0, 0]\n')
    assert main(["plan", str(bad)]) == 2
    assert f"{bad}: field 'workspace.min'" in capsys.readouterr().err
