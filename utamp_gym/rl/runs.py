"""A training run's files: the model zip with its `ModelMeta`, the evaluation episodes,
``train.json`` (`report`) and the finished run of a configuration (`finished_run`), shared by
`utamp_gym.rl.train`, `utamp_gym.rl.bc` and `utamp_gym.rl.seeds`.
"""

from __future__ import annotations

import json
import platform
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

from utamp_gym.env.object_space import slots_for_actions
from utamp_gym.rl.config import TrainConfig, TrainResult
from utamp_gym.rl.envs import EVAL_SEED_OFFSET, make_env, n_fluents
from utamp_gym.rl.saved import ModelMeta, write_meta


def model_meta(config: TrainConfig, env: Any) -> ModelMeta:
    """The `ModelMeta` of a run, read from its (unfiltered) evaluation env."""
    kitchen = env.unwrapped
    options: dict[str, Any] = {
        "masks": config.masks, "interface": config.interface, **config.env_options
    }  # fmt: skip
    if config.interface == "objects":  # the slot count the spaces were made for, explicitly
        options["slots"] = slots_for_actions(int(env.action_space.n))
    return ModelMeta(
        env_id=config.env_id,
        suite=str(kitchen.options.suite),
        algo="maskable-ppo" if config.algo == "bc" else config.algo,  # the model's class
        obs_keys=tuple(config.obs_keys),
        n_actions=int(env.action_space.n),
        n_fluents=n_fluents(env),
        env_options=options,
        trained_grounding=config.grounding,
    )


def save_model(model: Any, path: str | Path, meta: ModelMeta) -> None:
    """``model.save(path)`` plus the `ModelMeta` inside the zip."""
    model.save(path)
    write_meta(path, meta)


def eval_episodes_of(config: TrainConfig) -> list[tuple[str, int]]:
    """The (scene, seed) pairs of every evaluation: the env's scenes in turn."""
    # every observation entry: the env's default interface may have no ``symbolic`` entry;
    # the run's masks, so that the env reuses the run's (cached) action universe
    env = make_env(config.env_id, grounding="symbolic", num_objects=config.num_objects,
                   obs_keys=None, masks=config.masks, **config.env_options)  # fmt: skip
    names = [s.name for s in env.unwrapped.scenes]  # type: ignore[attr-defined]
    env.close()
    base = config.seed + EVAL_SEED_OFFSET
    return [(names[i % len(names)], base + i) for i in range(config.eval_episodes)]


def report(config: TrainConfig, hyper: dict[str, Any], result: TrainResult) -> dict[str, Any]:
    import sb3_contrib
    import stable_baselines3
    import torch

    data = asdict(result)
    data["out"], data["model_path"] = str(result.out), str(result.model_path)
    return {
        "config": {**asdict(config), "obs_keys": list(config.obs_keys)},
        "hyperparams": hyper,
        **data,
        "versions": {
            "python": platform.python_version(),
            "stable_baselines3": stable_baselines3.__version__,
            "sb3_contrib": sb3_contrib.__version__,
            "torch": torch.__version__,
        },
    }


#: `TrainConfig` fields added after runs were written, with their defaults
_LATER_FIELDS: dict[str, Any] = {"env_options": {}}


def seed_dir(out: str | Path, seed: int) -> Path:
    """Where `train_seeds` puts the run of one seed."""
    return Path(out) / f"seed_{seed}"


def finished_run(out: str | Path, config: TrainConfig) -> TrainResult | None:
    """The result of a finished run of exactly `config` in `out` (its ``train.json`` and
    ``model.zip``), or None."""
    out = Path(out)
    report_path = out / "train.json"
    if not report_path.is_file() or not (out / "model.zip").is_file():
        return None
    report = json.loads(report_path.read_text())
    want = {**asdict(config), "obs_keys": list(config.obs_keys)}
    have = dict(report.get("config") or {})
    for name, default in _LATER_FIELDS.items():  # a run written before the field existed
        have.setdefault(name, default)
    if have != want:
        return None
    names = {f.name for f in fields(TrainResult)}
    data = {k: v for k, v in report.items() if k in names}
    return TrainResult(**{**data, "out": out, "model_path": out / "model.zip"})
