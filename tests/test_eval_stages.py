"""Stage-wise scoring: failure stages, per-attribute accuracy, member alignment, row columns."""

from __future__ import annotations

import dataclasses

import pytest

from utamp_gym.eval.records import ResultRow, key_shard, read_rows, row_key, write_rows
from utamp_gym.eval.stages import ATTRIBUTES, failure_stage
from utamp_gym.eval.summary import summarize, to_markdown
from utamp_gym.methods.perceived import (
    align_members,
    attribute_accuracy,
    build_perceived_scene,
    rename_fact,
)
from utamp_gym.scene.catalogue import Member
from utamp_gym.scene.geometry import Box
from utamp_gym.suites import resolve_scene


@pytest.mark.parametrize(
    ("method", "kwargs", "stage"),
    [
        ("utamp2-perceived", {"success": True}, ""),
        ("utamp2-perceived", {"crashed": True}, "crash"),
        ("utamp2-perceived", {"solved": False, "affordance_f1": 0.9}, "perception"),
        ("utamp2-noisy", {"solved": True, "valid_gt": False, "affordance_f1": 0.97}, "perception"),
        ("utamp2-rules", {"solved": False, "affordance_f1": 0.95}, "affordances"),
        ("utamp2-gt", {"solved": False, "affordance_f1": 1.0}, "plan"),
        ("utamp1", {"solved": True, "valid_gt": False}, "plan"),
        ("utamp2-perceived", {"solved": True, "valid_gt": True, "affordance_f1": 0.9}, "physics"),
    ],
)
def test_failure_stage(method: str, kwargs: dict, stage: str) -> None:
    args = {
        "success": False,
        "crashed": False,
        "solved": False,
        "valid_gt": None,
        "affordance_f1": None,
        "grounding": "physics",
        **kwargs,
    }
    assert failure_stage(method, **args) == stage


def test_a_symbolic_invalid_plan_is_charged_to_its_affordances() -> None:
    args = {"success": False, "crashed": False, "solved": True, "valid_gt": False}
    assert failure_stage("utamp2-noisy", **args, affordance_f1=0.9, grounding="symbolic") == (
        "perception"
    )


def _row(**changes: object) -> ResultRow:
    base = ResultRow(
        scene="pick-place/000",
        suite="pick-place",
        n_objects=2,
        method="utamp2-perceived",
        seed=0,
        grounding="physics",
        noise=None,
        solved=True,
        success=False,
        failure_reason="step 1 (...): board rests inside tray instead of on top",
        plan_length=2,
        planning_time_s=3.0,
        execution_time_s=2.0,
        wall_time_s=5.0,
        affordance_precision=1.0,
        affordance_recall=0.96,
        affordance_f1=0.98,
        valid_gt=True,
        pose_noise=0.002,
        failure_stage="physics",
        acc_body=1.0,
        acc_material=0.5,
        acc_mass=0.25,
    )
    return dataclasses.replace(base, **changes)


def test_rows_keep_perception_stage_and_accuracy_columns(tmp_path) -> None:
    rows = [_row(), _row(scene="pick-place/001", perception="rgbd", acc_body=None)]
    path = tmp_path / "results.csv"
    write_rows(path, rows)
    back = read_rows(path)
    assert sorted(back, key=lambda r: r.scene) == sorted(rows, key=lambda r: r.scene)
    assert back[0].key != dataclasses.replace(back[0], perception="rgbd").key


def test_the_default_perception_keeps_old_keys_and_shards() -> None:
    key = row_key("pick-place/000", "utamp2-gt", 0, "physics", None, False, 0.0, 0.003)
    assert key[-1] == ""  # gaussian
    rgbd = row_key("pick-place/000", "utamp2-gt", 0, "physics", None, False, 0.0, 0.003, "rgbd")
    assert rgbd[-1] == "rgbd" and rgbd[:-1] == key[:-1]
    assert key_shard(key, 1000) == 564  # as before the option existed (test_eval_split)


def test_the_summary_groups_failures_by_stage_and_shows_attributes() -> None:
    rows = [_row(), _row(scene="pick-place/001", success=True, failure_stage="", failure_reason="")]
    summary = summarize(rows)
    (m,) = summary["methods"]
    assert m["failure_stages"] == {"physics": 1}
    assert m["attribute_accuracy"]["material"] == pytest.approx(0.5)
    text = to_markdown(summary)
    assert "## Failures by stage" in text and "## Per-attribute accuracy" in text


def test_alignment_pairs_members_by_overlap_not_by_name() -> None:
    declared = resolve_scene("kitchen-demo").catalogue["wooden-tray"]
    renamed = {
        {"handle-front": "handle-1", "handle-back": "handle-2"}.get(n, n): m._replace(
            name={"handle-front": "handle-1", "handle-back": "handle-2"}.get(n, n)
        )
        for n, m in declared.members.items()
    }
    extra = Member("edge-front", "edge", Box((0.16, -0.14, 0.0), (0.175, 0.14, 0.045)))
    perceived = declared._replace(members={**renamed, "edge-front": extra})
    pairs = align_members(perceived, declared)
    assert pairs["handle-1"] == "handle-front" and pairs["handle-2"] == "handle-back"
    assert "edge-front" not in pairs  # no declared member there: its facts are false positives
    fact = ("canGraspFrom", "tray-seen", "edge-front", "on", "front", "back")
    renamed_fact = rename_fact(fact, {"tray-seen": "wooden-tray"}, {"tray-seen": pairs})
    assert renamed_fact == ("canGraspFrom", "wooden-tray", "?edge-front", "on", "front", "back")


def test_a_perfect_perception_scores_one_on_every_attribute() -> None:
    scene = resolve_scene("kitchen-demo")
    seen = {o.name: scene.type_of(o.name) for o in scene.objects}
    ps = build_perceived_scene(scene, seen)
    assert all(ps.accuracy[a] == 1.0 for a in ATTRIBUTES)
    t = scene.type_of("mug")
    assert attribute_accuracy(t, t, {m: m for m in t.members})["members"] == 1.0
    assert ps.planning.type_of("mug").name == "mug-seen"


def test_the_perception_option_names_the_valid_modes() -> None:
    from utamp_gym.env.options import EnvOptions
    from utamp_gym.errors import UnknownNameError as Unknown
    from utamp_gym.errors import UtampError
    from utamp_gym.eval.sweep import SweepConfig

    with pytest.raises(Unknown, match="valid: gaussian, rgbd"):
        EnvOptions(suite="pick-place", objects=("tray", "pan"), perception="lidar")
    assert EnvOptions(suite="pick-place", objects=("tray", "pan"), perception="rgbd")
    with pytest.raises(UtampError, match="needs --grounding physics"):
        SweepConfig("pick-place", ("utamp2-gt",), grounding="symbolic", perception="rgbd")
