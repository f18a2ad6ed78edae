"""`utamp eval`: files and columns, resume, crash and dead-worker rows, notes, noise sweep."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

import pytest

from utamp_gym.cli import main
from utamp_gym.eval.records import COLUMNS, ResultsFile, read_rows
from utamp_gym.eval.runner import EvalTask, run_task
from utamp_gym.eval.sweep import SweepConfig, plan_tasks, run_sweep

REQUIRED = (
    "scene",
    "suite",
    "n_objects",
    "method",
    "seed",
    "solved",
    "success",
    "failure_reason",
    "plan_length",
    "planning_time_s",
    "execution_time_s",
    "affordance_precision",
    "affordance_recall",
    "affordance_f1",
)


def _dying_runner(task: EvalTask):  # module level: picklable for spawned workers
    if task.scene == "pick-place/001":
        os._exit(3)  # the worker process dies hard
    if task.scene == "pick-place/002":
        raise RuntimeError("boom")
    return run_task(task)


def test_cli_symbolic_eval_writes_all_files(tmp_path: Path, capsys) -> None:
    out = tmp_path / "tmp"
    args = ["eval", "--grounding", "symbolic", "--suite", "pick-place", "--limit", "5"]
    args += ["--methods", "utamp2-gt,utamp1", "--out", str(out), "--workers", "2", "--quiet"]
    assert main(args) == 0
    for name in (
        "results.csv",
        "summary.md",
        "summary.json",
        "success_by_objects.png",
        "planning_time_by_objects.png",
    ):
        assert (out / name).stat().st_size > 0, name
    with (out / "results.csv").open() as f:
        reader = csv.DictReader(f)
        assert set(REQUIRED) <= set(reader.fieldnames or ())
        rows = list(reader)
    assert len(rows) == 10
    assert {(r["method"], r["seed"]) for r in rows} == {("utamp2-gt", "0"), ("utamp1", "0")}
    gt = [r for r in rows if r["method"] == "utamp2-gt"]
    # the plan is played in the symbolic env: a few microseconds a step
    assert all(r["success"] == "true" and 0 < float(r["execution_time_s"]) < 1 for r in gt)
    assert all(float(r["affordance_f1"]) == 1.0 for r in gt)
    for r in rows:  # a failure always says why
        assert r["success"] == "true" or r["failure_reason"]
    summary = json.loads((out / "summary.json").read_text())
    labels = [m["label"] for m in summary["methods"]]
    assert labels == ["utamp2-gt", "utamp1"]
    assert summary["methods"][0]["success_rate"] == 1.0
    assert "planning_time_std_s" in summary["methods"][0]["by_objects"]["2"]
    assert "| utamp2-gt | 5 | 1.00 |" in (out / "summary.md").read_text()
    # the same command again resumes: nothing left to run
    capsys.readouterr()
    assert main(args) == 0
    assert "0 run(s), 10 resumed" in capsys.readouterr().out


def test_resume_skips_finished_rows(tmp_path: Path) -> None:
    cfg = SweepConfig("pick-place", ("utamp2-gt",), grounding="symbolic", limit=2)
    first = run_sweep(cfg, tmp_path, workers=0, progress=False)
    assert (first.ran, first.resumed) == (2, 0)
    called: list[str] = []

    def runner(task: EvalTask):
        called.append(task.scene)
        return run_task(task)

    bigger = SweepConfig("pick-place", ("utamp2-gt",), grounding="symbolic", limit=3)
    second = run_sweep(bigger, tmp_path, workers=0, progress=False, runner=runner)
    assert called == ["pick-place/002"]
    assert (second.ran, second.resumed) == (1, 2)
    assert len(read_rows(tmp_path / "results.csv")) == 3
    # another grounding is another key: nothing is skipped
    keys = {t.key for t in plan_tasks(SweepConfig("pick-place", ("utamp2-gt",), limit=3))[0]}
    assert not keys & set(ResultsFile(tmp_path / "results.csv").rows)


def test_crashes_and_dead_workers_become_failure_rows(tmp_path: Path) -> None:
    cfg = SweepConfig("pick-place", ("utamp2-gt",), grounding="symbolic", limit=4)
    report = run_sweep(cfg, tmp_path, workers=2, progress=False, runner=_dying_runner)
    rows = {r.scene: r for r in report.rows}
    assert len(rows) == 4
    assert (
        rows["pick-place/001"].crashed
        and "worker process died" in rows["pick-place/001"].failure_reason
    )
    assert (
        rows["pick-place/002"].crashed
        and "RuntimeError: boom" in rows["pick-place/002"].failure_reason
    )
    assert rows["pick-place/000"].success and rows["pick-place/003"].success
    assert len(read_rows(tmp_path / "results.csv")) == 4


def test_run_task_never_raises() -> None:
    row = run_task(EvalTask("pick-place/999", "utamp2-gt", grounding="symbolic"))
    assert row.crashed and not row.success
    assert "unknown scene 'pick-place/999'" in row.failure_reason


def test_torn_last_line_is_dropped(tmp_path: Path) -> None:
    cfg = SweepConfig("pick-place", ("utamp2-gt",), grounding="symbolic", limit=2)
    run_sweep(cfg, tmp_path, workers=0, progress=False)
    path = tmp_path / "results.csv"
    with path.open("a") as f:
        f.write("pick-place/005,pick-place,3,utamp2-gt,0,symb")  # killed mid-write
    results = ResultsFile(path)
    assert len(results.rows) == 2
    text = path.read_text()
    assert text.endswith("\n") and text.splitlines()[0] == ",".join(COLUMNS)


def test_utamp1_is_skipped_on_sliding_with_a_note() -> None:
    tasks, notes = plan_tasks(SweepConfig("sliding", ("utamp1", "utamp2-gt"), limit=2))
    assert {t.method for t in tasks} == {"utamp2-gt"}
    assert notes and "utamp1" in notes[0] and "sliding" in notes[0]


def test_noise_sweep_table_and_plot(tmp_path: Path) -> None:
    args = ["eval", "--grounding", "symbolic", "--suite", "pick-place", "--limit", "3"]
    args += ["--sweep-noise", "0,0.3", "--seeds", "2", "--workers", "0", "--quiet"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    sweep = summary["noise_sweep"]
    assert [s["noise"] for s in sweep] == [0.0, 0.3]
    assert sweep[0]["affordance_f1_mean"] == 1.0 and sweep[0]["success_rate"] == 1.0
    assert sweep[1]["affordance_f1_mean"] < 1.0
    assert (tmp_path / "success_vs_f1.png").stat().st_size > 0
    assert "Success rate against affordance F1" in (tmp_path / "summary.md").read_text()


def test_bad_arguments_exit_two(tmp_path: Path, capsys) -> None:
    base = ["eval", "--suite", "pick-place", "--out", str(tmp_path), "--quiet"]
    assert main([*base, "--methods", "utamp3"]) == 2
    assert "unknown method 'utamp3'" in capsys.readouterr().err
    assert main([*base, "--sweep-noise", "0,x"]) == 2


@pytest.mark.slow
@pytest.mark.physics
def test_physics_grounding_small(tmp_path: Path) -> None:
    cfg = SweepConfig("pick-place", ("utamp2-gt", "utamp2-noisy"), limit=1, noise=(0.0,))
    report = run_sweep(cfg, tmp_path, workers=2, progress=False)
    assert len(report.rows) == 2
    for row in report.rows:  # run_episode (gt) and a pre-computed plan (noise 0)
        assert row.grounding == "physics" and row.execution_time_s > 0
        assert row.success, row.failure_reason


@pytest.mark.parametrize(
    ("scene", "suite"),
    [
        ("pick-place/080", "pick-place"),
        ("procedural-v1/test-count/0003", "procedural-v1/test-count"),
        ("kitchen-demo", "custom"),
    ],
)
def test_a_row_names_the_suite_of_its_scene(scene: str, suite: str) -> None:
    """A procedural split is a suite of its own: its rows say which split they came from."""
    row = run_task(EvalTask(scene, "utamp2-gt", grounding="symbolic"))
    assert (row.suite, row.success) == (suite, True), row.failure_reason
