"""RL baselines: smoke trainings (MaskablePPO, PPO, DQN), loading, masked acting, the CLI."""

from __future__ import annotations

import argparse
import json
import shlex
from pathlib import Path

import gymnasium as gym
import pytest

pytest.importorskip("sb3_contrib")

import utamp_gym  # noqa: F401  (registers the env ids)
from utamp_gym.rl.cli import add_train_parser
from utamp_gym.rl.policy import RLPolicy, algo_of, evaluate_rl, load_rl_policy
from utamp_gym.rl.train import train

ROW_KEYS = {"scene", "n_objects", "seed", "success", "steps", "invalid_actions", "episode_time_s"}


@pytest.fixture(scope="module")
def maskable_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("maskable")
    train(
        algo="maskable-ppo", num_objects=3, steps=3_000, n_envs=2, seed=0, out=out,
        eval_every=1_500, eval_episodes=6, progress=False,
    )  # fmt: skip
    return out


def test_smoke_training_writes_outputs(maskable_run: Path) -> None:
    for name in ("model.zip", "learning_curve.png", "train.json"):
        assert (maskable_run / name).is_file()
    report = json.loads((maskable_run / "train.json").read_text())
    assert report["config"]["algo"] == "maskable-ppo" and report["config"]["num_objects"] == 3
    assert report["steps"] >= 3_000 and report["wall_time_s"] > 0
    assert 0.0 <= report["final_success"] <= 1.0
    assert [p["steps"] for p in report["curve"]] == sorted(p["steps"] for p in report["curve"])
    for point in report["curve"]:
        assert (maskable_run / point["checkpoint"]).is_file()
        assert point["invalid_actions"] == 0
    assert algo_of(maskable_run / "model.zip") == "maskable-ppo"


def test_saved_model_acts_on_masked_env_without_invalid_actions(maskable_run: Path) -> None:
    policy = load_rl_policy(maskable_run / "model.zip")
    env = gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=3)
    for episode in range(4):
        obs, info = env.reset(seed=episode)
        done = False
        while not done:
            action = policy(obs, info)
            assert info["action_mask"][action]
            obs, _, terminated, truncated, info = env.step(action)
            assert info["failure_reason"] is None
            done = terminated or truncated
    env.close()


def test_evaluate_rl_rows(maskable_run: Path) -> None:
    rows = evaluate_rl(maskable_run / "model.zip", num_objects=2, seeds=(0, 1))
    assert rows and all(set(r) >= ROW_KEYS for r in rows)
    assert {r["n_objects"] for r in rows} == {2} and {r["seed"] for r in rows} == {0, 1}
    assert sum(r["invalid_actions"] for r in rows) == 0
    scenes = [rows[0]["scene"]]
    assert [r["scene"] for r in evaluate_rl(maskable_run / "model.zip", scenes=scenes)] == scenes


@pytest.mark.parametrize("algo", ["ppo", "dqn"])
def test_unmasked_algorithms_train_and_load(tmp_path: Path, algo: str) -> None:
    hyper = {"learning_starts": 64} if algo == "dqn" else {"n_steps": 64, "batch_size": 64}
    result = train(
        algo=algo, num_objects=2, steps=512, n_envs=2, out=tmp_path, eval_every=256,
        eval_episodes=2, progress=False, hyperparams=hyper,
    )  # fmt: skip
    assert result.model_path.is_file() and result.steps >= 512
    assert algo_of(result.model_path) == algo
    masked = load_rl_policy(result.model_path)
    assert masked.algo == algo
    rows = evaluate_rl(masked, num_objects=2, seeds=(0,))
    assert sum(r["invalid_actions"] for r in rows) == 0  # masks applied at inference
    raw = evaluate_rl(result.model_path, num_objects=2, seeds=(0,), masks=False)
    assert all(set(r) >= ROW_KEYS for r in raw)


def test_rl_policy_needs_a_mask_source(maskable_run: Path) -> None:
    policy = load_rl_policy(maskable_run / "model.zip")
    env = gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=3)
    obs, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="action_mask"):
        policy(obs, {})
    with_env = RLPolicy(policy.model, env=env)
    assert env.unwrapped.action_masks()[with_env(obs, {})]
    assert isinstance(RLPolicy(policy.model, masks=False)(obs, None), int)


def test_train_parser_names() -> None:
    parser = argparse.ArgumentParser(prog="utamp")
    add_train_parser(parser.add_subparsers(dest="cmd", required=True))
    args = parser.parse_args(
        shlex.split(
            "train --env UTampKitchen-v0 --algo dqn --grounding physics --num-objects 4 "
            "--steps 1000 --envs 3 --seed 7 --out runs/x"
        )
    )
    got = (args.cmd, args.env, args.algo, args.grounding, args.num_objects, args.steps)
    assert got == ("train", "UTampKitchen-v0", "dqn", "physics", 4, 1000)
    assert (args.envs, args.seed, args.out) == (3, 7, "runs/x")
    assert callable(args.func)
    defaults = parser.parse_args(["train", "--out", "d"])
    got = (defaults.env, defaults.algo, defaults.grounding, defaults.num_objects)
    assert got == ("UTampKitchen-v0", "maskable-ppo", "symbolic", None)
    for bad in (["--algo", "sac"], ["--num-objects", "7"], ["--steps", "0"], []):
        with pytest.raises(SystemExit):
            parser.parse_args(["train", *bad, *(["--out", "d"] if bad else [])])


def test_bad_config_is_rejected(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="maskable-ppo"):
        train(algo="a2c", out=tmp_path, progress=False)
    with pytest.raises(ValueError, match="steps"):
        train(steps=0, out=tmp_path, progress=False)
