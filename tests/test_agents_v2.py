"""Goal-conditioned agents on procedural-v2: the training plumbing (`TrainConfig.env_options`,
the goal entries in the objects interface's keys, demos recorded in the goals env) and
benchmarks/agents_v2.py (its table from a measured one; a smoke run with tiny budgets)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

from utamp_gym.data.record import suite_env  # noqa: E402
from utamp_gym.env.object_goal import GOAL_KEYS  # noqa: E402
from utamp_gym.rl.config import TrainConfig  # noqa: E402
from utamp_gym.rl.envs import OBJECT_OBS_KEYS  # noqa: E402
from utamp_gym.rl.runs import finished_run  # noqa: E402
from utamp_gym.rl.saved import read_meta  # noqa: E402

bench = readme.load_script("benchmarks/agents_v2.py")


def test_each_procedural_split_records_in_its_own_versions_env() -> None:
    assert suite_env("procedural-v2/train") == (
        "UTampKitchenGoals-v0", {"split": "procedural-v2/train"}
    )  # fmt: skip
    assert suite_env("procedural-v2/test-count") == (
        "UTampKitchenGoals-v0", {"split": "procedural-v2/test-count"}
    )  # fmt: skip
    assert suite_env("procedural-v1/train") == ("UTampKitchenProcedural-v0", {"split": "train"})
    assert suite_env("procedural-v1/test-count") == (
        "UTampKitchenProcedural-v0", {"split": "test-count"}
    )  # fmt: skip


def test_goal_envs_train_on_the_goal_entries_and_save_their_options() -> None:
    goals = TrainConfig(env_id="UTampKitchenGoals-v0", interface="objects",
                        env_options={"slots": 8})  # fmt: skip
    assert goals.obs_keys == OBJECT_OBS_KEYS + GOAL_KEYS
    plain = TrainConfig(env_id="UTampKitchenProcedural-v0", interface="objects")
    assert plain.obs_keys == OBJECT_OBS_KEYS and plain.env_options == {}
    off = TrainConfig(env_id="UTampKitchenGoals-v0", interface="objects",
                      env_options={"goal_observation": False})  # fmt: skip
    assert off.obs_keys == OBJECT_OBS_KEYS
    with pytest.raises(ValueError, match=r"env_options must be a dict of gym\.make options"):
        TrainConfig(env_id="UTampKitchenGoals-v0", env_options={"masks": "none"})


def test_a_run_written_before_env_options_is_still_reused(tmp_path: Path) -> None:
    config = TrainConfig(env_id="UTampKitchenProcedural-v0", interface="objects")
    saved = {k: v for k, v in json.loads(json.dumps(config.__dict__)).items()}
    saved.pop("env_options")  # the train.json of a run before the field
    saved["obs_keys"] = list(config.obs_keys)
    result = {"steps": 1, "wall_time_s": 1.0, "train_time_s": 1.0, "final_success": 0.0,
              "steps_to_target": None, "time_to_target_s": None, "curve": []}  # fmt: skip
    (tmp_path / "train.json").write_text(json.dumps({"config": saved, **result}))
    (tmp_path / "model.zip").write_bytes(b"")
    assert finished_run(tmp_path, config) is not None
    other = TrainConfig(env_id="UTampKitchenProcedural-v0", interface="objects",
                        env_options={"slots": 8})  # fmt: skip
    assert finished_run(tmp_path, other) is None


def _seed(rates: dict[str, float], seed: int) -> dict[str, Any]:
    config = {"algo": "maskable-ppo", "steps": 100, "n_envs": 8, "eval_every": 10,
              "eval_episodes": 4, "time_limit_s": 60.0, "hyperparams": {}}  # fmt: skip
    return {"seed": seed, "steps": 100, "wall_time_s": 5.0, "curve": [], "config": config,
            "success": {s: {"rate": r, "n": 10, "successes": round(10 * r)}
                        for s, r in rates.items()}}  # fmt: skip


def test_table_has_every_split_intervals_and_the_train_to_test_tasks_gap(tmp_path: Path) -> None:
    splits = bench.split_suites()
    assert list(splits) == ["train", "test-instances", "test-families", "test-count",
                            "test-tasks"]  # fmt: skip
    seeds = [_seed({s: 0.4 for s in splits} | {"test-tasks": 0.1}, 0),
             _seed({s: 0.6 for s in splits} | {"test-tasks": 0.1}, 1)]  # fmt: skip
    planner = {"kind": "planner",
               "success": {s: {"rate": 0.9, "n": 10, "successes": 9} for s in splits}}  # fmt: skip
    table = {"env_id": bench.ENV_ID, "splits": splits, "limit": 10, "planner": bench.PLANNER,
             "achievable": {s: [9, 10] for s in splits}, "training_wall_time_s": 10.0,
             "load_average": {"start": [1, 1, 1], "end": [1, 1, 1]},
             "methods": {"MaskablePPO from scratch": {"kind": "learned", "per_seed": seeds},
                         "planner": planner}}  # fmt: skip
    bench.write(table, tmp_path)
    text = (tmp_path / "agents_v2.md").read_text()
    summary = json.loads((tmp_path / "agents_v2.json").read_text())["methods"][
        "MaskablePPO from scratch"]["summary"]  # fmt: skip
    assert summary["gap"]["mean"] == pytest.approx(0.4)  # (0.3 + 0.5) / 2
    assert summary["train"]["mean"] == pytest.approx(0.5)
    assert summary["train"]["t95_half_width"] == pytest.approx(12.706 * 0.1414 / 2**0.5, rel=1e-3)
    assert "| MaskablePPO from scratch | 2 | 0.50 ± 1.27 |" in text
    assert "+0.40 ± 1.27" in text and "test-count (9/10 achievable)" in text
    assert "goals reached / goals labelled achievable, per split: train 9/9, " in text
    assert "_Written by" in text


@pytest.mark.slow
def test_smoke_run_trains_evaluates_and_writes(tmp_path: Path) -> None:
    """The whole benchmark with tiny budgets (about two minutes)."""
    out, docs = tmp_path / "runs", tmp_path / "docs"
    cmd = [sys.executable, "benchmarks/agents_v2.py", "--seeds", "1", "--demos", "3",
           "--bc-epochs", "1", "--ppo-steps", "256", "--ft-steps", "128", "--envs", "2",
           "--eval-every", "128", "--eval-episodes", "2", "--limit", "1", "--out", str(out),
           "--docs", str(docs)]  # fmt: skip
    subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True, text=True)
    table = json.loads((docs / "agents_v2.json").read_text())
    assert set(table["methods"]) == {"BC from planner episodes", "MaskablePPO from scratch",
                                     "BC, then MaskablePPO", "planner (utamp2x-rules)"}  # fmt: skip
    ft = table["methods"]["BC, then MaskablePPO"]["per_seed"][0]["config"]
    assert ft["init_from"].endswith("bc/seed_0/model.zip") and ft["stop_at_plateau"] == 0.02
    assert (docs / "agents_v2_curves.png").is_file()
    for m in table["methods"].values():
        if m["kind"] == "learned":
            assert set(m["per_seed"][0]["success"]) == set(bench.split_suites())
            meta = read_meta(Path(m["per_seed"][0]["run"]) / "model.zip")
            assert meta.env_options["slots"] == 8 and set(GOAL_KEYS) <= set(meta.obs_keys)
    assert "gap train → test-tasks" in (docs / "agents_v2.md").read_text()
