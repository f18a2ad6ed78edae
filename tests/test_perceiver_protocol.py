"""The perceiver protocol: a user's perceiver loaded by name, scored with the stage-wise row."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

from utamp_gym.contract.perceiver import PerceivedAttributes, Perceiver
from utamp_gym.eval.runner import EvalTask, check_method, run_task
from utamp_gym.eval.stages import ATTRIBUTE_COLUMNS
from utamp_gym.methods.perceivers import (
    BuiltinPerceiver,
    PerceiverLoadError,
    _with_answer,
    load_perceiver,
    split_method,
)
from utamp_gym.perception.confidence import SIZE_COVERAGE, size_readings
from utamp_gym.scene.catalogue import load_catalogue

TESTS = Path(__file__).parent
USER = "utamp2-perceived:user_perceiver:CountingPerceiver"


@pytest.fixture(autouse=True)
def _importable(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TESTS))


def test_split_method() -> None:
    assert split_method(USER) == ("utamp2-perceived", "user_perceiver:CountingPerceiver")
    assert split_method("utamp2-perceived") == ("utamp2-perceived", None)
    assert split_method("rl:model.zip") == ("rl:model.zip", None)


def test_builtin_and_user_perceivers_satisfy_the_protocol() -> None:
    assert isinstance(BuiltinPerceiver(), Perceiver)
    assert isinstance(load_perceiver("user_perceiver:CountingPerceiver"), Perceiver)
    assert isinstance(load_perceiver(None), BuiltinPerceiver)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("user_perciever:CountingPerceiver", "named 'user_perciever'; did you mean user_perceiver"),
        ("user_perceiver:CountingPerciever", "did you mean CountingPerceiver"),
        ("user_perceiver:NotAPerceiver", "has no perceive(request) method"),
        ("vml", "did you mean vlm?"),
    ],
)  # fmt: skip
def test_load_errors_name_the_module_or_class(spec: str, message: str) -> None:
    with pytest.raises(PerceiverLoadError, match=None) as info:
        check_method("utamp2-perceived:" + spec)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_user_perceiver_produces_the_stage_wise_row() -> None:
    import user_perceiver

    before = user_perceiver.CountingPerceiver.calls
    row = run_task(EvalTask("pick-place/000", USER, 0, "symbolic"))
    assert user_perceiver.CountingPerceiver.calls == before + 1  # the protocol was called
    assert row.method == USER and not row.crashed, row.failure_reason
    assert row.success and row.failure_stage == ""
    assert row.affordance_f1 == pytest.approx(1.0)
    for col in ATTRIBUTE_COLUMNS:  # attributes -> affordances -> plan -> (physics)
        assert 0.0 <= getattr(row, col) <= 1.0


def test_a_perceiver_that_sees_nothing_is_lost_at_perception() -> None:
    blind = "utamp2-perceived:user_perceiver:BlindPerceiver"
    row = run_task(EvalTask("pick-place/000", blind, 0, "physics", pose_noise=0.0))
    assert not row.success and not row.crashed
    assert row.failure_stage == "perception"
    assert "no camera saw" in row.failure_reason


def test_cli_eval_loads_a_user_perceiver(tmp_path: Path) -> None:
    env = {"PYTHONPATH": f"{TESTS.parent}:{TESTS}", "PATH": "/usr/bin:/bin"}
    cmd = [sys.executable, "-m", "utamp_gym.cli", "eval", "--suite", "pick-place"]
    cmd += ["--scenes", "pick-place/000", "--grounding", "symbolic", "--methods", USER]
    cmd += ["--out", str(tmp_path), "--workers", "1", "--quiet"]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    with open(tmp_path / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["method"] for r in rows] == [USER]
    assert rows[0]["success"] == "true" and rows[0]["acc_robustness"] != ""

    typo = USER.replace("Counting", "Countng")
    bad = [typo if a == USER else str(tmp_path / "x") if a == str(tmp_path) else a for a in cmd]
    done = subprocess.run(bad, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert "did you mean CountingPerceiver" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_reports_carry_confidences() -> None:
    a = PerceivedAttributes(_type(), {"mass": 0.4})
    assert a.confidence_of("mass") == 0.4 and a.confidence_of("material") == 1.0


def _type():  # a catalogue type to report about
    return load_catalogue()["glass-mug"]


def test_a_vlm_answer_is_certain_and_the_geometry_keeps_its_reading_error() -> None:
    t = load_catalogue()["glass-mug"]
    seen = PerceivedAttributes(
        t, {"material": 0.5, "member_size": SIZE_COVERAGE},
        {"material": ("ceramic",), "member_size": size_readings(t)},
    )  # fmt: skip
    entry = {"name": "mug", "material": "Ceramic", "mass_kg": 0.4, "robustness": "fragile"}
    got = _with_answer(seen, entry, "mug")
    assert (got.type.material, got.type.mass) == ("ceramic", 0.4)
    assert got.confidence == {"member_size": SIZE_COVERAGE}  # the answer itself is certain
    narrow, wide = got.alternatives["member_size"]
    assert (narrow.material, wide.mass) == ("ceramic", 0.4)  # readings of the answered type
    assert narrow.members == size_readings(t)[0].members
    assert _with_answer(PerceivedAttributes(t), entry, "mug").alternatives == {}
