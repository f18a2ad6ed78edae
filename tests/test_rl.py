"""RL baselines: smoke trainings (MaskablePPO, PPO, DQN), loading, masked acting, the CLI,
saved env options, several seeds, and saved agents in `utamp eval` (``rl:PATH``)."""

from __future__ import annotations

import argparse
import csv
import json
import shlex
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from procs import user_env

pytest.importorskip("sb3_contrib")

import utamp_gym  # noqa: F401  (registers the env ids)
from utamp_gym.cli import main
from utamp_gym.env.options import MASKS
from utamp_gym.eval.sweep import SweepConfig
from utamp_gym.rl.cli import MASK_CHOICES, add_train_parser
from utamp_gym.rl.config import TrainConfig
from utamp_gym.rl.harness import STEPS_PER_OBJECT
from utamp_gym.rl.policy import RLPolicy, algo_of, evaluate_rl, load_rl_policy
from utamp_gym.rl.runs import finished_run
from utamp_gym.rl.saved import META_NAME, ModelError, read_meta, write_meta
from utamp_gym.rl.seeds import train_seed
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
            assert info["failure_reason"] == ""
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
def test_unmasked_algorithms_train_and_load(
    tmp_path: Path, algo: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    hyper = {"learning_starts": 64} if algo == "dqn" else {"n_steps": 64, "batch_size": 64}
    temp = tmp_path / "tmp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))  # where SB3 puts a run's default logs
    result = train(
        algo=algo, num_objects=2, steps=512, n_envs=2, out=tmp_path / "run", eval_every=256,
        eval_episodes=2, progress=False, hyperparams=hyper,
    )  # fmt: skip
    assert result.model_path.is_file() and result.steps >= 512
    assert not list(temp.glob("SB3-*")), "a training leaves no SB3 log folder behind"
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
    assert (defaults.masks, defaults.seeds) == ("affordances", 1)
    extra = parser.parse_args(["train", "--masks", "geometric", "--seeds", "3", "--out", "d"])
    assert (extra.masks, extra.seeds) == ("geometric", 3)
    assert MASK_CHOICES == MASKS  # the parser's copy of the env option's values
    for bad in (
        ["--algo", "sac"],
        ["--num-objects", "7"],
        ["--steps", "0"],
        ["--masks", "oracle"],
        ["--seeds", "0"],
        [],
    ):
        with pytest.raises(SystemExit):
            parser.parse_args(["train", *bad, *(["--out", "d"] if bad else [])])


def test_bad_config_is_rejected(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="maskable-ppo"):
        train(algo="a2c", out=tmp_path, progress=False)
    with pytest.raises(ValueError, match="steps"):
        train(steps=0, out=tmp_path, progress=False)
    with pytest.raises(ValueError, match="affordances, geometric, none"):
        train(masks="oracle", out=tmp_path, progress=False)


def test_saved_model_predicts_on_raw_env_observations(maskable_run: Path) -> None:
    """The observation filter travels with the model: SB3's own predict on gym.make's obs."""
    from sb3_contrib import MaskablePPO

    model = MaskablePPO.load(maskable_run / "model.zip", device="cpu")
    env = gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=3)
    obs, info = env.reset(seed=0)
    assert {"object_poses", "robot"} <= set(obs)  # entries the model was not trained on
    action, _ = model.predict(obs, action_masks=info["action_mask"], deterministic=True)
    assert info["action_mask"][int(action)]
    env.close()


def test_models_and_checkpoints_carry_their_env(maskable_run: Path) -> None:
    meta = read_meta(maskable_run / "model.zip")
    assert (meta.env_id, meta.suite, meta.algo, meta.masks) == (
        "UTampKitchen-v0", "pick-place", "maskable-ppo", "affordances"
    )  # fmt: skip
    assert meta.obs_keys == ("symbolic", "present") and meta.n_actions == 206
    for ckpt in (maskable_run / "checkpoints").glob("*.zip"):
        assert read_meta(ckpt) == meta
    assert load_rl_policy(maskable_run / "model.zip").meta == meta


def test_model_without_metadata_is_a_clear_error(tmp_path: Path, maskable_run: Path) -> None:
    bare = tmp_path / "bare.zip"
    with zipfile.ZipFile(maskable_run / "model.zip") as src, zipfile.ZipFile(bare, "w") as dst:
        for item in src.infolist():
            if item.filename != META_NAME:
                dst.writestr(item, src.read(item.filename))
    with pytest.raises(ModelError, match=r"has no utamp_env\.json"):
        read_meta(bare)
    assert algo_of(bare) == "maskable-ppo"  # still loadable by the policy class
    with pytest.raises(ModelError, match="does not exist"):
        read_meta(tmp_path / "missing.zip")
    with pytest.raises(ModelError, match=r"has no utamp_env\.json"):
        SweepConfig(suite="pick-place", methods=(f"rl:{bare}",))


def test_eval_rejects_a_model_that_does_not_fit(tmp_path: Path, maskable_run: Path) -> None:
    model = tmp_path / "model.zip"
    model.write_bytes((maskable_run / "model.zip").read_bytes())
    with pytest.raises(ModelError, match=r"suite 'pick-place'.*'sliding' suite"):
        SweepConfig(suite="sliding", methods=(f"rl:{model}",))
    meta = read_meta(model)
    write_meta(model, type(meta)(**{**meta.to_json(), "n_actions": 207, "obs_keys": ("x",)}))
    with pytest.raises(ModelError, match="expects 207 actions"):
        SweepConfig(suite="pick-place", methods=(f"rl:{model}",))
    err = main(["eval", "--suite", "pick-place", "--methods", f"rl:{model}", "--out",
                str(tmp_path / "e"), "--quiet"])  # fmt: skip
    assert err == 2


@pytest.fixture(scope="module")
def cli_runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`utamp train` with geometric masks and two seeds (a smoke budget)."""
    out = tmp_path_factory.mktemp("geometric")
    args = (
        "train --algo maskable-ppo --masks geometric --num-objects 2 --steps 1024 --envs 2 "
        f"--seed 3 --seeds 2 --eval-every 512 --eval-episodes 5 --no-progress --out {out}"
    )
    assert main(shlex.split(args)) == 0
    return out


def test_train_seeds_writes_runs_and_an_aggregate(cli_runs: Path) -> None:
    agg = json.loads((cli_runs / "aggregate.json").read_text())
    assert agg["seeds"] == [3, 4] and agg["config"]["masks"] == "geometric"
    assert (cli_runs / "learning_curves.png").stat().st_size > 0
    finals = []
    for seed in (3, 4):
        report = json.loads((cli_runs / f"seed_{seed}" / "train.json").read_text())
        assert report["config"]["seed"] == seed and report["config"]["masks"] == "geometric"
        finals.append(report["final_success"])
        assert read_meta(cli_runs / f"seed_{seed}" / "model.zip").masks == "geometric"
    assert agg["final_success"]["mean"] == pytest.approx(np.mean(finals))
    assert [r["seed"] for r in agg["per_seed"]] == [3, 4]
    assert 0 <= agg["reached"] <= 2


def _eval_rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize(
    "grounding", ["symbolic", pytest.param("physics", marks=pytest.mark.physics)]
)
def test_utamp_eval_runs_a_trained_agent_next_to_the_planner(
    cli_runs: Path, tmp_path: Path, grounding: str
) -> None:
    model = cli_runs / "seed_3" / "model.zip"
    limit = "5" if grounding == "symbolic" else "1"
    args = (
        f"eval --suite pick-place --methods utamp2-gt,rl:{model} --grounding {grounding} "
        f"--limit {limit} --workers 0 --quiet --out {tmp_path}"
    )
    assert main(shlex.split(args)) == 0
    rows = _eval_rows(tmp_path)
    assert {r["method"] for r in rows} == {"utamp2-gt", f"rl:{model}"}
    assert len(rows) == 2 * int(limit)
    for r in rows:
        if r["method"].startswith("rl:"):
            steps = int(r["plan_length"])
            assert 1 <= steps <= STEPS_PER_OBJECT * int(r["n_objects"])
            assert r["crashed"] == "false" and r["grounding"] == grounding
            assert (r["success"] == "true") == (r["failure_reason"] == "")
            assert len(r["plan"].split(" ; ")) == steps
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert {m["method"] for m in summary["methods"]} == {"utamp2-gt", f"rl:{model}"}


def test_a_finished_seed_is_reused_not_retrained(cli_runs: Path) -> None:
    run = cli_runs / "seed_3"
    before = (run / "model.zip").stat().st_mtime_ns
    kwargs = {
        "algo": "maskable-ppo", "masks": "geometric", "num_objects": 2, "steps": 1024,
        "n_envs": 2, "eval_every": 512, "eval_episodes": 5, "progress": False,
    }  # fmt: skip
    result = train_seed(3, cli_runs, **kwargs)
    assert result.out == run and (run / "model.zip").stat().st_mtime_ns == before
    assert result.curve == json.loads((run / "train.json").read_text())["curve"]
    options = {k: v for k, v in kwargs.items() if k != "progress"}
    assert finished_run(run, TrainConfig(**{**options, "seed": 3, "steps": 2048})) is None


def test_train_seeds_as_parallel_ray_tasks(
    cli_runs: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`utamp train --seeds 2 --executor ray --workers 2` trains both seeds as Ray tasks on a
    2-CPU instance it starts (and stops) and learns exactly what the same seeds learned one
    after another in this process."""
    ray = pytest.importorskip("ray")
    if ray.is_initialized():
        ray.shutdown()
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    args = (
        "train --algo maskable-ppo --masks geometric --num-objects 2 --steps 1024 --envs 2 "
        "--seed 3 --seeds 2 --eval-every 512 --eval-episodes 5 --no-progress "
        f"--executor ray --workers 2 --out {tmp_path}"
    )
    assert main(shlex.split(args)) == 0
    assert not ray.is_initialized()
    agg = json.loads((tmp_path / "aggregate.json").read_text())
    assert agg["seeds"] == [3, 4]
    for seed in (3, 4):
        here = json.loads((cli_runs / f"seed_{seed}" / "train.json").read_text())
        there = json.loads((tmp_path / f"seed_{seed}" / "train.json").read_text())
        assert there["config"] == here["config"]
        assert [p["success_rate"] for p in there["curve"]] == [
            p["success_rate"] for p in here["curve"]
        ]
        assert _weights(tmp_path / f"seed_{seed}") == _weights(cli_runs / f"seed_{seed}")


def _weights(run: Path) -> dict[str, list[float]]:
    """The trained policy's parameters in a saved model, as plain lists."""
    import io

    import torch

    with zipfile.ZipFile(run / "model.zip") as z:
        state = torch.load(io.BytesIO(z.read("policy.pth")), weights_only=True)
    return {k: v.flatten().tolist() for k, v in state.items()}


def test_train_executor_options_need_several_seeds(tmp_path: Path, capsys) -> None:
    args = f"train --steps 64 --executor ray --out {tmp_path}"
    assert main(shlex.split(args)) == 2
    assert "need --seeds K > 1" in capsys.readouterr().err


def test_worker_envs_of_the_utamp_process_find_the_env_ids() -> None:
    """A spawned worker inherits the `utamp` command's argv, so `import utamp_gym` registers
    nothing there (`utamp train --grounding physics` uses such workers)."""
    code = (
        "import sys; sys.argv[0] = 'utamp'\n"
        "from utamp_gym.rl.envs import make_vec_env\n"
        "vec = make_vec_env('UTampKitchen-v0', 1, subproc=True, num_objects=2)\n"
        "print(sorted(vec.reset()))\n"
        "vec.close()\n"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], env=user_env(), capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "['present', 'symbolic']"


def test_a_model_of_one_interface_names_both_on_the_others_observation() -> None:
    """SB3's predict and `RLPolicy` on an observation of the other env interface: an error
    naming the interface the model was trained on and the observation's (was KeyError)."""
    from sb3_contrib import MaskablePPO

    from utamp_gym.rl.envs import OBJECT_OBS_KEYS, make_env
    from utamp_gym.rl.policies import MaskableKeysPolicy
    from utamp_gym.rl.slots import SlotPolicy

    grounded = MaskablePPO(MaskableKeysPolicy, make_env("UTampKitchen-v0", num_objects=3),
                           n_steps=64, batch_size=64, device="cpu")  # fmt: skip
    objects_env = make_env("UTampKitchenProcedural-v0", obs_keys=OBJECT_OBS_KEYS)
    slots = MaskablePPO(SlotPolicy, objects_env, n_steps=64, batch_size=64, device="cpu")
    procedural = gym.make("UTampKitchenProcedural-v0", grounding="symbolic")  # objects
    kitchen = gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=3)  # grounded
    cases = [(grounded, procedural, "grounded", "objects", "'symbolic'"),
             (slots, kitchen, "objects", "grounded", "'attributes'")]  # fmt: skip
    for model, env, trained, seen, lacks in cases:
        obs, info = env.reset(seed=0)
        match = (
            rf"trained on the {trained} interface, but this observation comes from the {seen} "
            rf"interface \(it lacks {lacks}.*interface='{trained}'"
        )
        with pytest.raises(ModelError, match=match):
            model.predict(obs, action_masks=info["action_mask"])
        with pytest.raises(ModelError, match=match):
            RLPolicy(model)(obs, info)
    obs, info = procedural.reset(seed=0)  # the matching pair still acts
    assert info["action_mask"][int(slots.predict(obs, action_masks=info["action_mask"])[0])]
