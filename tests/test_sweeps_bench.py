"""benchmarks/sweeps.py: the run-or-read loop of the split sweeps (no ``utamp eval`` run here)."""

from __future__ import annotations

import csv
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

sweeps = readme.load_script("benchmarks/sweeps.py")
v1 = readme.load_script("benchmarks/procedural_sweep.py")
v2 = readme.load_script("benchmarks/v2_physics.py")


def _write_rows(folder: Path, scenes: list[str]) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    with (folder / "results.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["scene", "seed"])
        w.writeheader()
        w.writerows({"scene": s, "seed": "0"} for s in scenes)


def _summarize(split: str, rows: list[dict[str, str]]) -> dict[str, object]:
    return {"split": split, "scenes": [r["scene"] for r in rows]}


def _command(split: str, args) -> list[str]:
    return ["eval", "--suite", f"s/{split}", "--out", str(Path(args.out) / split)]


def test_summarize_only_reads_each_split_in_order_and_runs_nothing(tmp_path, monkeypatch) -> None:
    _write_rows(tmp_path / "b", ["b0", "b1"])
    _write_rows(tmp_path / "a", ["a0"])

    def no_run(*args, **kwargs):
        raise AssertionError("--summarize-only ran a command")

    monkeypatch.setattr(subprocess, "run", no_run)
    parser = sweeps.sweep_parser("x", seeds=1, splits=("a",), out=str(tmp_path))
    args = parser.parse_args(["--summarize-only", "--splits", " b, ,a"])
    assert sweeps.sweep_splits(args, _command, _summarize) == [
        {"split": "b", "scenes": ["b0", "b1"]},
        {"split": "a", "scenes": ["a0"]},
    ]


def test_each_split_is_run_before_its_rows_are_read(tmp_path, monkeypatch, capsys) -> None:
    ran = []

    def fake_run(cmd: list[str], check: bool) -> None:
        assert check and cmd[:3] == [sys.executable, "-m", "utamp_gym.cli"]
        ran.append(cmd[3:])
        out = Path(cmd[cmd.index("--out") + 1])
        _write_rows(out, [f"{out.name}-scene"])  # the run writes what is read next

    monkeypatch.setattr(subprocess, "run", fake_run)
    args = sweeps.sweep_parser("x", seeds=1, splits=("p", "q"), out=str(tmp_path)).parse_args([])
    summaries = sweeps.sweep_splits(args, _command, _summarize)
    assert [s["scenes"] for s in summaries] == [["p-scene"], ["q-scene"]]
    assert [c[2] for c in ran] == ["s/p", "s/q"]
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == f"utamp eval --suite s/p --out {tmp_path / 'p'}"


def test_a_missing_split_folder_is_an_error_naming_it(tmp_path) -> None:
    args = sweeps.sweep_parser("x", seeds=1, splits=("gone",), out=str(tmp_path)).parse_args(
        ["--summarize-only"]
    )
    with pytest.raises(FileNotFoundError, match="gone"):
        sweeps.sweep_splits(args, _command, _summarize)


def test_both_sweeps_run_their_suite_method_in_physics() -> None:
    for bench, suite, method in ((v1, "procedural-v1", "utamp2-rules"),
                                 (v2, "procedural-v2", "utamp2x-rules")):  # fmt: skip
        args = bench.build_parser().parse_args(["--seeds", "2", "--out", "o"])
        cmd = bench.eval_command("train", args)
        assert cmd[:5] == ["eval", "--suite", f"{suite}/train", "--methods", method]
        assert cmd[cmd.index("--seeds") + 1] == "2" and "physics" in cmd
        assert cmd[cmd.index("--out") + 1] == str(Path("o") / "train")


def test_failure_kinds_drop_step_names_and_numbers() -> None:
    assert sweeps.reason_kind("step 3 (pick obj2 x): obj2 slipped 1.5 cm (contacts: a~b)") == (
        "X slipped # cm"
    )


def test_failure_kinds_are_listed_by_count_then_name() -> None:
    kinds = [Counter({"b": 1, "c": 2}), Counter({"a": 1, "d": 1})]
    assert sweeps.by_count(kinds) == ["c", "a", "b", "d"]
