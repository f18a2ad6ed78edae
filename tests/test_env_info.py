"""env/info.py: a `StepRecord` in the info dict's fixed structure."""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.backend import MacroResult
from utamp_gym.env.info import TIMING_KEYS, EpisodeInfo, StepRecord, split_atoms

MASK = np.array([True, False])


def _info() -> EpisodeInfo:
    return EpisodeInfo("s1", ["a", "b"], ("(on a b)",), "put a on b")


def test_a_record_of_nothing_fills_every_entry_with_its_empty_value() -> None:
    info = _info()(StepRecord(mask=MASK, success=False))
    assert info == {
        "action": "", "action_mask": MASK, "failure_reason": "", "timings": {},
        "macro_result": {"executed": False, "success": False, "reason": "", "retries": ""},
        "unexpected_atoms": "", "anomalies": {"a": "", "b": ""}, "fault": "", "scene": "s1",
        "is_success": False, "goal": ("(on a b)",), "instruction": "put a on b",
    }  # fmt: skip


def test_every_field_of_a_step_reaches_its_entry() -> None:
    step = StepRecord(
        mask=MASK,
        success=np.bool_(True),
        action="(pick a)",
        failure="a slipped",
        timings={"ik_s": 0.5},
        macro=MacroResult(False, "a slipped", retries=("missed", "tilted")),
        unexpected=("+(on a b)", "-(clear b)"),
        anomalies={"b": "no symbol"},
        fault="drop",
    )
    info = _info()(step)
    texts = [info[k] for k in ("action", "failure_reason", "fault")]
    assert texts == ["(pick a)", "a slipped", "drop"]
    assert info["timings"] == {k: 0.5 if k == "ik_s" else 0.0 for k in TIMING_KEYS}
    assert info["macro_result"] == {
        "executed": True, "success": False, "reason": "a slipped", "retries": "missed; tilted"
    }  # fmt: skip
    assert split_atoms(info["unexpected_atoms"]) == ["+(on a b)", "-(clear b)"]
    assert info["anomalies"] == {"a": "", "b": "no symbol"}
    assert info["is_success"] is True


def test_each_info_is_a_fresh_dict_and_a_record_is_keyword_only() -> None:
    episode = _info()
    first = episode(StepRecord(mask=MASK, success=False))
    first["anomalies"]["a"] = "changed by a caller"
    first["macro_result"]["executed"] = True
    second = episode(StepRecord(mask=MASK, success=False))
    assert second["anomalies"]["a"] == "" and second["macro_result"]["executed"] is False
    with pytest.raises(TypeError):
        StepRecord(MASK, False)  # type: ignore[misc]
