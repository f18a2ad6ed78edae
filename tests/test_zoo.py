"""The RL Baselines3 Zoo recipe: MaskablePPO registered in rl-zoo3, trained by the zoo's own
`train` on UTampKitchen-v0 with the packaged hyperparameters, and scored with masks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rl_zoo3")
pytest.importorskip("sb3_contrib")

from utamp_gym.rl import zoo


def test_zoo_trains_and_evaluates_maskable_ppo_with_masks(tmp_path: Path) -> None:
    args = [
        "train", "--algo", "maskable-ppo", "--env", "UTampKitchen-v0", "-f", str(tmp_path),
        "-n", "512", "--seed", "0", "--eval-freq", "512", "--eval-episodes", "2",
        "--hyperparams", "n_envs:2", "n_steps:256",
    ]  # fmt: skip
    assert zoo.main(args) == 0
    import rl_zoo3
    import rl_zoo3.exp_manager
    from sb3_contrib.common.maskable.callbacks import MaskableEvalCallback

    assert rl_zoo3.ALGOS["maskable-ppo"].__name__ == "MaskablePPO"
    assert rl_zoo3.exp_manager.EvalCallback is MaskableEvalCallback  # the zoo evaluates masked
    run = tmp_path / "maskable-ppo" / "UTampKitchen-v0_1"
    assert zoo.run_model(run).name == "UTampKitchen-v0.zip"
    evaluations = np.load(run / "evaluations.npz")
    assert evaluations["timesteps"].tolist() == [512]
    report = zoo.evaluate(run, episodes=4)
    assert report["env_kwargs"]["grounding"] == "symbolic" and report["episodes"] == 4
    assert 0.0 <= report["masked_success"] <= 1.0 and report["invalid_actions"] == 0
    assert report["env_kwargs"]["masks"] == "geometric"


def test_eval_env_gets_the_hyperparameter_files_env_kwargs() -> None:
    args = ["--env", "UTampKitchen-v0", "--conf-file", str(zoo.HYPERPARAMS)]
    extra = zoo._eval_env_kwargs(args)
    assert extra[0] == "--eval-env-kwargs"
    assert "grounding:'symbolic'" in extra and "masks:'geometric'" in extra
    assert zoo._eval_env_kwargs([*args, "--env-kwargs", "masks:'none'"]) == []
