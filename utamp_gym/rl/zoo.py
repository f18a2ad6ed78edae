"""RL Baselines3 Zoo with MaskablePPO: a launcher that trains with the zoo and scores with masks.

Why: rl-zoo3 (2.9.2) has no MaskablePPO in its algorithm table, and both its periodic
evaluation (SB3's ``EvalCallback``) and ``enjoy`` call ``model.predict`` without action masks,
so a masked agent can be neither trained nor scored there as documented. This launcher

* registers sb3-contrib's MaskablePPO as the zoo algorithm ``maskable-ppo``, replaces the
  zoo's evaluation callback by sb3-contrib's ``MaskableEvalCallback`` (masks on), gives the
  evaluation env the hyperparameter file's env kwargs (rl-zoo3 2.9.2 passes it only those of
  the command line), then runs the zoo's own ``train`` with the given arguments (``train``);
* scores a trained zoo run with masks (``evaluate``): the deterministic policy picks among the
  actions ``info["action_mask"]`` shows, over fixed (scene, seed) episodes, and reports the
  masked success rate (and sb3-contrib's masked ``evaluate_policy`` mean reward).

Usage (the ``zoo`` extra: ``pip install 'utamp-gym[zoo]'``)::

    python -m utamp_gym.rl.zoo train --algo maskable-ppo --env UTampKitchen-v0 \\
        --conf-file utamp_gym/rl/zoo_maskable_ppo.yml -f logs/ --seed 0
    python -m utamp_gym.rl.zoo evaluate --run logs/maskable-ppo/UTampKitchen-v0_1 --episodes 60

``train`` accepts every option of ``python -m rl_zoo3.train`` (``--conf-file`` defaults to the
packaged `HYPERPARAMS`); the env kwargs (symbolic grounding, geometric masks, reward shaping)
come from the hyperparameter file.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from utamp_gym.env.registry import register_envs
from utamp_gym.extras import MissingExtraError, require
from utamp_gym.rl.policy import RLPolicy, run_episodes

HYPERPARAMS = Path(__file__).with_name("zoo_maskable_ppo.yml")
ALGO = "maskable-ppo"


def register() -> None:
    """MaskablePPO in the zoo's algorithm table; masked evaluation during training."""
    require("utamp_gym.rl.zoo", "zoo", "rl")
    import rl_zoo3
    import rl_zoo3.exp_manager
    import rl_zoo3.utils
    from sb3_contrib import MaskablePPO
    from sb3_contrib.common.maskable.callbacks import MaskableEvalCallback

    register_envs()
    for table in (rl_zoo3.utils.ALGOS, rl_zoo3.ALGOS):
        table[ALGO] = MaskablePPO
    rl_zoo3.exp_manager.EvalCallback = MaskableEvalCallback  # type: ignore[attr-defined]


def train(argv: Sequence[str]) -> None:
    """The zoo's ``train`` with MaskablePPO registered (`register`)."""
    register()
    from rl_zoo3.train import train as zoo_train

    args = list(argv)
    if "--conf-file" not in args and "-conf" not in args:
        args += ["--conf-file", str(HYPERPARAMS)]
    if "--eval-env-kwargs" not in args:
        args += _eval_env_kwargs(args)
    before = sys.argv
    sys.argv = ["rl_zoo3.train", *args]
    try:
        zoo_train()
    finally:
        sys.argv = before


def _eval_env_kwargs(args: list[str]) -> list[str]:
    """``--eval-env-kwargs`` repeating the hyperparameter file's ``env_kwargs``: rl-zoo3 2.9.2
    builds its evaluation env with the command line's env kwargs only, so without this the
    evaluation env has the env id's defaults (physics grounding, affordance masks) and its
    observations do not fit the model."""
    import yaml

    def value(*flags: str) -> str | None:
        for i, a in enumerate(args[:-1]):
            if a in flags:
                return args[i + 1]
        return None

    conf, env = value("--conf-file", "-conf"), value("--env") or "CartPole-v1"
    if conf is None or "--env-kwargs" in args:
        return []
    kwargs = (yaml.safe_load(Path(conf).read_text()).get(env) or {}).get("env_kwargs") or {}
    return ["--eval-env-kwargs", *(f"{k}:{v!r}" for k, v in kwargs.items())] if kwargs else []


def run_model(run: Path) -> Path:
    """The final model of a zoo run folder (``<env>.zip``), else its best model."""
    models = sorted(p for p in run.glob("*.zip") if p.stem != "best_model")
    if models:
        return models[0]
    if (run / "best_model.zip").is_file():
        return run / "best_model.zip"
    raise FileNotFoundError(f"{run}: no model zip (is it a zoo run folder?)")


def evaluate(run: str | Path, episodes: int = 60, seed: int = 10_000) -> dict[str, Any]:
    """Masked evaluation of a zoo run: success rate and mean reward with masks on."""
    import gymnasium as gym
    import yaml
    from sb3_contrib import MaskablePPO
    from sb3_contrib.common.maskable.evaluation import evaluate_policy
    from stable_baselines3.common.monitor import Monitor

    register()
    run = Path(run)
    saved = run / run.name.rsplit("_", 1)[0]
    # the zoo writes these with Python tags (OrderedDict) and reads them as we do here
    args = yaml.load((saved / "args.yml").read_text(), Loader=yaml.UnsafeLoader)
    config = yaml.load((saved / "config.yml").read_text(), Loader=yaml.UnsafeLoader)
    env_id = dict(args)["env"]
    env_kwargs = dict(dict(config).get("env_kwargs") or {})
    env_kwargs.update(reward_shaping=False, terminate_on_failure=False)
    model = MaskablePPO.load(run_model(run), device="cpu")
    env = Monitor(gym.make(env_id, **env_kwargs))
    try:
        names = [s.name for s in env.unwrapped.scenes]  # type: ignore[attr-defined]
        pairs = [(names[i % len(names)], seed + i) for i in range(episodes)]
        rows = run_episodes(env, RLPolicy(model, masks=True), pairs)
        mean, std = evaluate_policy(model, env, n_eval_episodes=min(episodes, 10),
                                    deterministic=True, use_masking=True)  # fmt: skip
    finally:
        env.close()
    return {
        "run": str(run), "env_id": env_id, "env_kwargs": env_kwargs, "episodes": len(rows),
        "masked_success": sum(r["success"] for r in rows) / len(rows),
        "invalid_actions": sum(r["invalid_actions"] for r in rows),
        "masked_mean_reward": float(mean), "masked_std_reward": float(std),
    }  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m utamp_gym.rl.zoo``; without the extra: one line naming it, exit code 2."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        require("python -m utamp_gym.rl.zoo", "zoo", "rl")
    except MissingExtraError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if argv[:1] == ["train"]:
        train(argv[1:])
        return 0
    parser = argparse.ArgumentParser(prog="python -m utamp_gym.rl.zoo", description=__doc__)
    sub = parser.add_subparsers(dest="cmd", required=True)
    sub.add_parser("train", help="the zoo's train, with MaskablePPO registered")
    ev = sub.add_parser("evaluate", help="masked success of a zoo run folder")
    ev.add_argument("--run", required=True, help="logs/maskable-ppo/<env>_<n>")
    ev.add_argument("--episodes", type=int, default=60)
    ev.add_argument("--seed", type=int, default=10_000)
    args = parser.parse_args(argv)
    report = evaluate(args.run, args.episodes, args.seed)
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
