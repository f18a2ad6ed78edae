"""Agents of the objects interface: a slot-policy MaskablePPO trained for a few hundred steps on
one suite runs unmodified on the others (``utamp eval --methods rl:PATH``), and one trained on
``procedural-v1/train`` on every test split and on `UTampKitchen-v0`; behaviour cloning from
`utamp demos` and MaskablePPO fine-tuning from the cloned policy."""

from __future__ import annotations

import csv
import io
import json
import shlex
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("sb3_contrib")
pytest.importorskip("minari")

from utamp_gym.cli import main
from utamp_gym.env.objects import N_ACTIONS
from utamp_gym.env.registry import register_envs
from utamp_gym.rl.policy import load_rl_policy
from utamp_gym.rl.saved import read_meta
from utamp_gym.rl.train import train

register_envs()


def _rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as f:
        return list(csv.DictReader(f))


def _weights(path: Path) -> dict[str, np.ndarray]:
    import torch

    with zipfile.ZipFile(path) as z:
        state = torch.load(io.BytesIO(z.read("policy.pth")), weights_only=True)
    return {k: v.numpy().copy() for k, v in state.items()}


@pytest.fixture(scope="module")
def slot_agent(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("slots")
    train(
        algo="maskable-ppo", masks="geometric", interface="objects", steps=384, n_envs=2,
        seed=0, out=out, eval_every=384, eval_episodes=3, progress=False,
    )  # fmt: skip
    return out / "model.zip"


def test_the_saved_agent_names_the_objects_interface(slot_agent: Path) -> None:
    meta = read_meta(slot_agent)
    # the slot count is recorded too (a model's slots default from it: tests/test_rl_slots.py)
    assert meta.env_options == {"masks": "geometric", "interface": "objects", "slots": 6}
    assert meta.n_actions == N_ACTIONS and meta.n_fluents == 0


@pytest.mark.parametrize("suite", ["sliding", "extra"])
def test_an_agent_trained_on_one_suite_runs_on_others(
    slot_agent: Path, tmp_path: Path, suite: str
) -> None:
    args = (
        f"eval --suite {suite} --methods utamp2-gt,rl:{slot_agent} --grounding symbolic "
        f"--limit 3 --workers 0 --quiet --out {tmp_path}"
    )
    assert main(shlex.split(args)) == 0
    agent = [r for r in _rows(tmp_path) if r["method"].startswith("rl:")]
    assert len(agent) == 3
    for r in agent:
        assert r["crashed"] == "false" and r["suite"] == suite and int(r["plan_length"]) >= 1
        assert (r["success"] == "true") == (r["failure_reason"] == "")


def test_the_same_policy_acts_on_every_registered_suite(slot_agent: Path) -> None:
    policy = load_rl_policy(slot_agent)
    for env_id in ("UTampKitchen-v0", "UTampKitchenSlide-v0"):
        env = gym.make(env_id, grounding="symbolic", masks="geometric", interface="objects")
        obs, info = env.reset(seed=1)
        action = policy(obs, info)
        assert info["action_mask"][action]  # masked inference: an action the mask shows
        env.step(action)


@pytest.fixture(scope="module")
def procedural_agent(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The slot MaskablePPO after 384 steps on ``procedural-v1/train`` (the env's default)."""
    out = tmp_path_factory.mktemp("procedural")
    result = train(
        env_id="UTampKitchenProcedural-v0", algo="maskable-ppo", masks="geometric",
        interface="objects", steps=384, n_envs=2, seed=0, out=out, eval_every=384,
        eval_episodes=3, progress=False, hyperparams={"n_steps": 192, "batch_size": 128},
    )  # fmt: skip
    assert result.steps == 384
    return out / "model.zip"


def test_a_policy_trained_on_the_procedural_train_split(procedural_agent: Path) -> None:
    meta = read_meta(procedural_agent)
    assert meta.env_id == "UTampKitchenProcedural-v0" and meta.suite == "procedural-v1/train"
    assert meta.n_actions == N_ACTIONS


@pytest.mark.parametrize("split", ["test-families", "test-count"])
def test_it_runs_unmodified_on_the_test_splits(
    procedural_agent: Path, tmp_path: Path, split: str
) -> None:
    suite = f"procedural-v1/{split}"
    args = (
        f"eval --suite {suite} --methods rl:{procedural_agent} --grounding symbolic "
        f"--limit 3 --workers 0 --quiet --out {tmp_path}"
    )
    assert main(shlex.split(args)) == 0
    rows = _rows(tmp_path)
    assert [r["scene"] for r in rows] == [f"{suite}/{i:04d}" for i in range(3)]
    for r in rows:
        assert r["crashed"] == "false"
        assert (r["success"] == "true") == (r["failure_reason"] == "")
        plan = r["plan"].split(" ; ")
        assert len(plan) == int(r["plan_length"]) >= 1
        # every step was a ground action of this scene's objects (6 of them in test-count)
        objects = {f"obj{i}" for i in range(1, 6)} | {"base"}
        assert all(a.strip("()").split()[1] in objects for a in plan)
    if split == "test-count":
        assert {r["n_objects"] for r in rows} == {"6"}


def test_it_acts_on_every_split_and_on_the_paper_suites(procedural_agent: Path) -> None:
    policy = load_rl_policy(procedural_agent)
    envs = [("UTampKitchenProcedural-v0", {"split": s}) for s in
            ("test-instances", "test-families", "test-count")]  # fmt: skip
    envs.append(("UTampKitchen-v0", {"interface": "objects"}))
    chosen = []
    for env_id, options in envs:
        env = gym.make(env_id, grounding="symbolic", masks="geometric", **options)
        obs, info = env.reset(seed=3)
        for _ in range(3):  # a few steps: the policy acts on the states its actions lead to
            action = policy(obs, info)
            assert info["action_mask"][action]  # masked inference: an action the mask shows
            chosen.append(int(action))
            obs, _reward, terminated, truncated, info = env.step(action)
            assert info["action"] and isinstance(info["is_success"], bool)
            if terminated or truncated:
                break
        env.close()
    assert len(set(chosen)) > 1  # it reads the observation: not one constant index


@pytest.fixture(scope="module")
def demos(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("demos")
    assert main(shlex.split(f"demos --suite pick-place --episodes 6 --out {root}")) == 0
    return root / "utamp" / "pick-place-macro-utamp2-gt-v0"


def test_behaviour_cloning_then_fine_tuning(demos: Path, tmp_path: Path) -> None:
    bc = tmp_path / "bc"
    args = (
        f"train --algo bc --interface objects --masks geometric --demos {demos} "
        f"--eval-episodes 4 --no-progress --out {bc}"
    )
    assert main(shlex.split(args)) == 0
    report = json.loads((bc / "train.json").read_text())
    assert report["config"]["algo"] == "bc" and report["steps"] > 0
    fit = report["hyperparams"]  # the demonstrations were fitted
    assert fit["final_loss"] < 0.8 * fit["first_epoch_loss"]
    assert read_meta(bc / "model.zip").algo == "maskable-ppo"
    # fine-tuning starts from the cloned weights (a zero learning rate keeps them)
    tuned = tmp_path / "tuned"
    train(
        algo="maskable-ppo", masks="geometric", interface="objects", steps=128, n_envs=2,
        seed=0, out=tuned, eval_every=128, eval_episodes=2, progress=False,
        init_from=str(bc / "model.zip"), hyperparams={"learning_rate": 0.0, "n_steps": 64},
    )  # fmt: skip
    before, after = _weights(bc / "model.zip"), _weights(tuned / "model.zip")
    assert before.keys() == after.keys()
    assert all(np.array_equal(before[k], after[k]) for k in before)


def test_bc_needs_demos_and_the_objects_interface(tmp_path: Path, capsys) -> None:
    assert main(shlex.split(f"train --algo bc --out {tmp_path}")) == 2
    assert "needs demos" in capsys.readouterr().err
