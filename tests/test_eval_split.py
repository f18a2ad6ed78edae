"""Sweeps that split and merge: --seed-offset, --scenes, --shard, `utamp eval merge`, and the
executor choice (`--executor ray` without Ray installed)."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest
from procs import user_env

from utamp_gym.cli import main
from utamp_gym.errors import UnknownNameError, UtampError
from utamp_gym.eval.merge import MergeConflictError, merge_outputs
from utamp_gym.eval.records import key_shard, read_rows, row_key
from utamp_gym.eval.sweep import SweepConfig, parse_shard, plan_tasks, select_scenes

SYMBOLIC = ["eval", "--suite", "pick-place", "--grounding", "symbolic", "--quiet"]


def test_shard_of_a_run_key_is_a_fixed_hash() -> None:
    """Shards must agree between machines and Python processes: no salted hash()."""
    keys = {
        row_key("pick-place/000", "utamp2-gt", 0, "physics", None, False, 0.0, 0.003): 564,
        row_key("pick-place/105", "utamp2-noisy", 3, "symbolic", 0.01, False, 0.0, None): 195,
        row_key("sliding/041", "utamp1", 7, "physics", None, True, 0.1, 0.005): 794,
    }
    for key, shard in keys.items():
        assert key_shard(key, 1000) == shard
        assert key_shard(key, 1) == 0
    code = (
        "from utamp_gym.eval.sweep import SweepConfig, plan_tasks; "
        "cfg = SweepConfig('pick-place', ('utamp2-gt',), seeds=3, shard=(2, 3)); "
        "print(sorted(t.scene + '#' + str(t.seed) for t in plan_tasks(cfg)[0]))"
    )
    outs = set()
    for hash_seed in ("1", "2"):
        env = user_env(PYTHONHASHSEED=hash_seed)
        res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
        outs.add(res.stdout)
    here = plan_tasks(SweepConfig("pick-place", ("utamp2-gt",), seeds=3, shard=(2, 3)))[0]
    assert outs == {f"{sorted(t.scene + '#' + str(t.seed) for t in here)}\n"}


def test_shards_partition_the_sweep() -> None:
    base = SweepConfig("pick-place", ("utamp2-gt", "utamp2-noisy"), seeds=2, noise=(0.0, 0.1))
    every = {t.key for t in plan_tasks(base)[0]}
    assert len(every) == 106 * 3 * 2
    parts = [
        {t.key for t in plan_tasks(SweepConfig(**{**base.__dict__, "shard": (i, 4)}))[0]}
        for i in range(1, 5)
    ]
    assert set().union(*parts) == every
    assert sum(len(p) for p in parts) == len(every)  # disjoint
    assert all(abs(len(p) - len(every) / 4) < 0.15 * len(every) / 4 for p in parts)


def test_seed_offset_and_scene_glob() -> None:
    cfg = SweepConfig("pick-place", ("utamp2-gt",), seeds=3, seed_offset=5, scenes="pick-place/00*")
    tasks, _ = plan_tasks(cfg)
    assert {t.seed for t in tasks} == {5, 6, 7}
    assert sorted({t.scene for t in tasks}) == [f"pick-place/00{i}" for i in range(10)]
    limited = SweepConfig("sliding", ("utamp2-gt",), scenes="sliding/0[23]?", limit=4)
    assert [s.name for s in select_scenes(limited)] == [f"sliding/02{i}" for i in range(4)]
    with pytest.raises(UtampError, match=r"matches no scene.*pick-place/000, pick-place/001"):
        select_scenes(SweepConfig("pick-place", scenes="sliding/*"))
    with pytest.raises(UtampError, match="--seed-offset must be at least 0"):
        SweepConfig("pick-place", seed_offset=-1)


@pytest.mark.parametrize("text", ["0/3", "4/3", "a/3", "3", "1/2/3", ""])
def test_bad_shard_is_an_error(text: str) -> None:
    with pytest.raises(UtampError, match="--shard"):
        parse_shard(text)


def test_shard_parses() -> None:
    assert parse_shard("2/3") == (2, 3) and parse_shard("1/1") == (1, 1)


def test_cli_split_arguments_exit_two(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    base = [*SYMBOLIC, "--out", str(tmp_path)]
    assert main([*base, "--shard", "4/3"]) == 2
    assert "--shard I/N needs 1 <= I <= N" in capsys.readouterr().err
    assert main([*base, "--scenes", "kitchen*"]) == 2
    err = capsys.readouterr().err
    assert "--scenes 'kitchen*' matches no scene" in err and "pick-place/000" in err
    assert main([*base, "--ray-address", "127.0.0.1:1"]) == 2
    assert "--ray-address needs --executor ray" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_info:
        main(["eval", "--suite", "pick-place"])
    assert exit_info.value.code == 2
    assert "required: --out" in capsys.readouterr().err


def test_executor_ray_without_ray_exits_two(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` now raises ImportError
    assert main([*SYMBOLIC, "--limit", "1", "--executor", "ray", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "pip install 'utamp-gym[ray]'" in err
    assert not (tmp_path / "results.csv").exists()  # failed before any work


def test_unknown_executor_lists_the_valid_ones() -> None:
    from utamp_gym.distributed import make_executor

    with pytest.raises(UnknownNameError, match="unknown executor 'dask'; valid: local, ray"):
        make_executor("dask")


def _rows(path: Path) -> list[dict[str, str]]:
    return [r.outcome() for r in read_rows(path / "results.csv")]


def test_three_shards_merge_to_the_unsharded_sweep(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Both CLI forms: `utamp eval --shard I/3 ...` three times, then `utamp eval merge`."""
    sweep = [*SYMBOLIC, "--methods", "utamp2-gt,utamp2-noisy", "--noise", "0.1"]
    sweep += ["--scenes", "pick-place/00[0-5]", "--seeds", "2", "--seed-offset", "4"]
    sweep += ["--workers", "0", "--no-explain"]
    assert main([*sweep, "--out", str(tmp_path / "whole")]) == 0
    for i in (1, 2, 3):
        assert main([*sweep, "--shard", f"{i}/3", "--out", str(tmp_path / f"s{i}")]) == 0
    sizes = [len(read_rows(tmp_path / f"s{i}" / "results.csv")) for i in (1, 2, 3)]
    assert sum(sizes) == 6 * 2 * 2 and min(sizes) > 0
    shard_summary = json.loads((tmp_path / "s2" / "summary.json").read_text())
    assert shard_summary["shard"] == "2/3" and shard_summary["seed_offset"] == 4
    capsys.readouterr()
    parts = [str(tmp_path / f"s{i}") for i in (3, 1, 2)]
    assert main(["eval", "merge", str(tmp_path / "merged"), *parts, "--quiet"]) == 0
    assert "merged 24 run(s) from 3 folder(s)" in capsys.readouterr().out
    assert _rows(tmp_path / "merged") == _rows(tmp_path / "whole")
    whole = json.loads((tmp_path / "whole" / "summary.json").read_text())
    merged = json.loads((tmp_path / "merged" / "summary.json").read_text())
    assert merged["merged_from"] == parts and merged["seeds"] == 2 and merged["seed_offset"] == 4
    for a, b in zip(whole["methods"], merged["methods"], strict=True):
        for key in ("label", "runs", "successes", "success_rate_ci95", "failures", "by_objects"):
            if key == "by_objects":  # equal rates; timing intervals differ run to run
                assert {n: d["success_rate_ci95"] for n, d in a[key].items()} == {
                    n: d["success_rate_ci95"] for n, d in b[key].items()
                }
            else:
                assert a[key] == b[key], key
    for name in ("summary.md", "success_by_objects.png", "planning_time_by_objects.png"):
        assert (tmp_path / "merged" / name).stat().st_size > 0
    # merging again, with a shard listed twice and OUT among the inputs, changes nothing
    again = [str(tmp_path / "merged"), str(tmp_path / "merged"), *parts, parts[0]]
    assert main(["eval", "merge", *again, "--quiet"]) == 0
    assert "(24 duplicate(s) dropped)" in capsys.readouterr().out
    assert _rows(tmp_path / "merged") == _rows(tmp_path / "whole")


def _copy_with_changed_row(src: Path, dst: Path, column: str, value: str) -> None:
    dst.mkdir()
    with (src / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    rows[0][column] = value
    with (dst / "results.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def test_merge_conflicts_and_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = [*SYMBOLIC, "--methods", "utamp2-gt", "--limit", "2", "--workers", "0"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    scene = read_rows(tmp_path / "a" / "results.csv")[0].scene
    # only wall-clock columns differ: the same run, merged once
    _copy_with_changed_row(tmp_path / "a", tmp_path / "timing", "wall_time_s", "99")
    summary = merge_outputs(tmp_path / "m1", [tmp_path / "a", tmp_path / "timing"])
    assert summary["runs"] == 2 and summary["duplicate_rows"] == 2
    # a different outcome: refused, naming the run, the column and both folders
    _copy_with_changed_row(tmp_path / "a", tmp_path / "b", "success", "false")
    with pytest.raises(MergeConflictError) as info:
        merge_outputs(tmp_path / "m2", [tmp_path / "a", tmp_path / "b"])
    msg = str(info.value)
    assert f"scene={scene}, method=utamp2-gt, seed=0, grounding=symbolic" in msg
    assert str(tmp_path / "a") in msg and str(tmp_path / "b") in msg
    assert "success: 'true' vs 'false'" in msg
    assert not (tmp_path / "m2" / "results.csv").exists()
    merge_cli = ["eval", "merge", str(tmp_path / "m3"), str(tmp_path / "a"), str(tmp_path / "b")]
    assert main(merge_cli) == 2
    assert "conflicting rows for run" in capsys.readouterr().err
    # OUT holding other results is not overwritten; a folder without results is named
    with pytest.raises(UtampError, match=r"already holds a results\.csv"):
        merge_outputs(tmp_path / "a", [tmp_path / "timing"])
    with pytest.raises(UtampError, match=r"nowhere: no results\.csv"):
        merge_outputs(tmp_path / "m4", [tmp_path / "a", tmp_path / "nowhere"])
    # one summary per suite and grounding
    _copy_with_changed_row(tmp_path / "a", tmp_path / "p", "grounding", "physics")
    with pytest.raises(UtampError, match="several groundings"):
        merge_outputs(tmp_path / "m5", [tmp_path / "a", tmp_path / "p"])


def test_interrupted_eval_exits_130_with_a_resume_hint(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import utamp_gym.eval.sweep as sweep

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(sweep, "run_sweep", interrupted)
    assert main([*SYMBOLIC, "--limit", "1", "--out", str(tmp_path)]) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and "to resume" in err and "Traceback" not in err
