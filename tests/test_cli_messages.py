"""Messages that must not mislead: the tower's base by name and type, the training summary
line, unknown scene names with the nearest valid ones, and utamp1's absent affordance scores."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from utamp_gym.cli import main
from utamp_gym.errors import UnknownNameError
from utamp_gym.eval.records import ResultRow
from utamp_gym.eval.summary import summarize, to_markdown
from utamp_gym.suites import UnknownSceneError, nearest_scene_names, resolve_scene

BOARD_SCENE = "procedural-v1/test-count/0007"  # its base is a chopping board


def test_run_names_the_tower_base_and_its_type(capsys) -> None:
    scene = resolve_scene(BOARD_SCENE)
    base_type = scene.type_of(scene.tower_base).name
    assert base_type.startswith("chopping-board")
    assert main(["run", BOARD_SCENE]) == 0
    out = capsys.readouterr().out
    assert f"  tower on {scene.tower_base} ({base_type}): " in out
    assert "tray" not in out


def test_an_unreached_goal_names_the_base() -> None:
    from utamp_gym.agents.runs import execute_plan

    ex = execute_plan(resolve_scene(BOARD_SCENE), [])  # nothing moves: obj5 starts on the base
    assert ex.failure_reason == f"goal not reached: base holds {ex.final_stack}"


def test_summary_header_names_the_base_of_procedural_scenes() -> None:
    row = ResultRow(
        scene=BOARD_SCENE, suite="procedural-v1/test-count", n_objects=6, method="utamp2-gt",
        seed=0, grounding="physics", noise=None, solved=True, success=True, failure_reason="",
        plan_length=16, planning_time_s=0.07, execution_time_s=4.0, wall_time_s=4.1,
        affordance_precision=1.0, affordance_recall=1.0, affordance_f1=1.0,
    )  # fmt: skip
    for suite, base in (("procedural-v1/test-count", "each scene's base object (`goal_base`)"),
                        ("pick-place", "the tray")):  # fmt: skip
        context = {"suite": suite, "grounding": "physics"}
        md = to_markdown(summarize([row], context=context))
        assert f"every step executed in MuJoCo and the tower stands on {base}." in md


def test_train_prints_the_target_it_missed(capsys, tmp_path: Path) -> None:
    pytest.importorskip("sb3_contrib")
    args = ["train", "--num-objects", "2", "--steps", "64", "--envs", "1", "--eval-every", "64",
            "--eval-episodes", "2", "--no-progress", "--out", str(tmp_path)]  # fmt: skip
    assert main(args) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    report = json.loads((tmp_path / "train.json").read_text())
    target = f"target success {report['config']['target_success']:.2f}"
    if report["steps_to_target"] is None:
        assert f"; {target} not reached; model: " in line
    else:
        assert f"; {target} reached at {report['steps_to_target']} steps (" in line
    assert re.match(r"maskable-ppo: \d+ steps in [\d.]+ s, final success [\d.]+; target", line)


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("kitchen-dmeo", "unknown scene 'kitchen-dmeo'; did you mean kitchen-demo?"),
        ("Kitchen-Demo", "unknown scene 'Kitchen-Demo'; did you mean kitchen-demo?"),
        ("pick-place/17", "unknown scene 'pick-place/17'; did you mean pick-place/017?"),
        ("sliding/0004", "unknown scene 'sliding/0004'; did you mean sliding/004?"),
        ("procedural-v1/train/7",
         "unknown scene 'procedural-v1/train/7'; did you mean procedural-v1/train/0007?"),
        ("procedural-v1/trian/0001",
         "unknown scene 'procedural-v1/trian/0001'; did you mean procedural-v1/train/0001, "),
    ],
)  # fmt: skip
def test_unknown_scene_names_suggest_the_nearest_in_one_line(
    capsys, name: str, message: str
) -> None:
    assert main(["run", name]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"utamp: error: {message}") and err.count("\n") == 1
    assert "extra/0" not in err  # not a list of the first 40 names
    with pytest.raises(UnknownNameError):  # the API raises the same
        resolve_scene(name)


def test_an_out_of_range_number_gets_the_suite_range_and_nonsense_every_range() -> None:
    with pytest.raises(UnknownSceneError) as info:
        resolve_scene("pick-place/999")
    text = str(info.value)
    assert text.startswith("unknown scene 'pick-place/999'; did you mean pick-place/099")
    assert text.endswith(" (pick-place has pick-place/000 to 105)")
    with pytest.raises(UnknownSceneError) as info:
        resolve_scene("xyzzy")
    assert str(info.value) == (
        "unknown scene 'xyzzy'; valid: kitchen-demo, pick-place/000 to 105, sliding/000 to 041, "
        "extra/000 to 083, procedural-v1/train/0000 to 0224, procedural-v1/test-instances/0000 "
        "to 0107, procedural-v1/test-families/0000 to 0107, procedural-v1/test-count/0000 to "
        "0107, procedural-v2/train/0000 to 0399, procedural-v2/test-instances/0000 to 0099, "
        "procedural-v2/test-families/0000 to 0099, procedural-v2/test-count/0000 to 0099, "
        "procedural-v2/test-tasks/0000 to 0099, procedural-v2/hard/0000 to 0041 or a scene file "
        "(.toml)"
    )
    assert info.value.suggestions == [] and "pick-place/017" in info.value.valid
    assert nearest_scene_names("pick-place/0017", ["pick-place/017"]) == ["pick-place/017"]


def test_plan_json_has_no_affordance_scores_for_utamp1(capsys) -> None:
    keys = ("affordance_precision", "affordance_recall", "affordance_f1")
    assert main(["plan", "kitchen-demo", "--method", "utamp1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] and [data[k] for k in keys] == [None, None, None]
    assert main(["plan", "kitchen-demo", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [data[k] for k in keys] == [1.0, 1.0, 1.0]
