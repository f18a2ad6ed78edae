"""`train`: MaskablePPO, PPO or DQN on a kitchen env, with evaluation, checkpoints and a curve.

Why three algorithms: MaskablePPO is the baseline (it samples only applicable actions, from
`action_masks()`); PPO and DQN learn the same task without masks, which measures what the
masks are worth. All three get the same reward, ``reward_shaping=True`` (+1 goal, +0.1 per
new tower object, −0.01 per failed action) without ``terminate_on_failure``: an unmasked
agent then pays for invalid actions but keeps exploring until the time limit, whereas ending
the episode at the first of them (2–5 of the ~200 actions apply) would leave it almost no
chance to reach a rewarded state. Evaluation uses the deterministic policy with masks for
every algorithm (PPO/DQN pick the best applicable action; ``eval_masks=False`` turns
that off) on a fixed cycle of the env's scenes.

Outputs in `out`: ``model.zip`` (final), ``checkpoints/step_<n>.zip`` (at every
evaluation), ``learning_curve.png`` and ``train.json`` (config, steps, wall times, curve).
"""

from __future__ import annotations

import json
import platform
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from utamp_gym.rl.envs import DEFAULT_OBS_KEYS, EVAL_SEED_OFFSET, make_env, make_vec_env
from utamp_gym.rl.policy import ALGOS, algo_class

GROUNDINGS = ("symbolic", "physics")


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a run (written to ``train.json``).

    `num_objects` None trains on every scene of the suite (2–5 objects); `hyperparams`
    overrides `default_hyperparams`; `obs_keys` are the observation entries the agent sees.
    """

    env_id: str = "UTampKitchen-v0"
    algo: str = "maskable-ppo"
    grounding: str = "symbolic"
    num_objects: int | None = None
    steps: int = 200_000
    n_envs: int = 8
    seed: int = 0
    eval_every: int = 10_000
    eval_episodes: int = 60
    eval_masks: bool = True
    target_success: float = 0.9
    stop_at_target: bool = False
    reward_shaping: bool = True
    terminate_on_failure: bool = False
    obs_keys: tuple[str, ...] = DEFAULT_OBS_KEYS
    hyperparams: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.algo not in ALGOS:
            raise ValueError(f"unknown algo {self.algo!r}; valid: {', '.join(ALGOS)}")
        if self.grounding not in GROUNDINGS:
            raise ValueError(f"unknown grounding {self.grounding!r}; valid: symbolic, physics")
        for name in ("steps", "n_envs", "eval_every", "eval_episodes"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)}")


@dataclass(frozen=True)
class TrainResult:
    """What `train` produced: paths, steps, times and the evaluation curve.

    `wall_time_s` is the whole call; `train_time_s` leaves out the evaluations and
    checkpoints, as do the curve's times and `time_to_target_s` (training time until the
    first evaluation with success ≥ `TrainConfig.target_success`).
    """

    out: Path
    model_path: Path
    steps: int
    wall_time_s: float
    train_time_s: float
    final_success: float
    steps_to_target: int | None
    time_to_target_s: float | None
    curve: list[dict[str, Any]]


def default_hyperparams(algo: str, n_envs: int) -> dict[str, Any]:
    """The algorithm settings used unless `TrainConfig.hyperparams` overrides them."""
    net = {"net_arch": [128, 128]}
    if algo == "dqn":
        return {
            "learning_rate": 1e-4, "buffer_size": 100_000, "learning_starts": 1_000,
            "batch_size": 64, "gamma": 0.99, "train_freq": 4, "target_update_interval": 1_000,
            "exploration_fraction": 0.3, "exploration_final_eps": 0.05, "policy_kwargs": net,
        }  # fmt: skip
    return {
        "learning_rate": 3e-4, "n_steps": max(16, 1024 // n_envs), "batch_size": 256,
        "n_epochs": 10, "gamma": 0.99, "gae_lambda": 0.95, "ent_coef": 0.01,
        "policy_kwargs": net,
    }  # fmt: skip


def eval_episodes_of(config: TrainConfig) -> list[tuple[str, int]]:
    """The (scene, seed) pairs of every evaluation: the env's scenes in turn."""
    env = make_env(config.env_id, grounding="symbolic", num_objects=config.num_objects)
    names = [s.name for s in env.unwrapped.scenes]  # type: ignore[attr-defined]
    env.close()
    base = config.seed + EVAL_SEED_OFFSET
    return [(names[i % len(names)], base + i) for i in range(config.eval_episodes)]


def train(
    env_id: str = "UTampKitchen-v0",
    algo: str = "maskable-ppo",
    grounding: str = "symbolic",
    num_objects: int | None = None,
    steps: int = 200_000,
    n_envs: int = 8,
    seed: int = 0,
    out: str | Path = "runs/rl",
    eval_every: int = 10_000,
    eval_episodes: int = 60,
    *,
    progress: bool = True,
    verbose: int = 0,
    **options: Any,
) -> TrainResult:
    """Train `algo` on `env_id` and write the outputs to `out` (see the module docstring).

    `options` are the other `TrainConfig` fields (``eval_masks``, ``target_success``,
    ``stop_at_target``, ``reward_shaping``, ``terminate_on_failure``, ``obs_keys``,
    ``hyperparams``). Physics grounding trains in ``SubprocVecEnv`` workers.
    """
    import torch

    from utamp_gym.rl.callbacks import PeriodicEval, ProgressBar, plot_learning_curve

    config = TrainConfig(
        env_id=env_id, algo=algo, grounding=grounding, num_objects=num_objects, steps=steps,
        n_envs=n_envs, seed=seed, eval_every=eval_every, eval_episodes=eval_episodes,
        **options,
    )  # fmt: skip
    torch.set_num_threads(1)
    out = Path(out)
    (out / "checkpoints").mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()

    env_kw: dict[str, Any] = {"grounding": grounding, "num_objects": num_objects}
    vec = make_vec_env(
        env_id, n_envs, seed=seed, subproc=grounding == "physics", obs_keys=config.obs_keys,
        reward_shaping=config.reward_shaping, terminate_on_failure=config.terminate_on_failure,
        **env_kw,
    )  # fmt: skip
    eval_env = make_env(env_id, obs_keys=None, **env_kw)
    hyper = {**default_hyperparams(algo, n_envs), **config.hyperparams}
    model = algo_class(algo)("MultiInputPolicy", vec, seed=seed, verbose=verbose, **hyper)
    evaluator = PeriodicEval(
        eval_env, eval_episodes_of(config), out, eval_every,
        masks=config.eval_masks, stop_at=config.target_success if config.stop_at_target else None,
    )  # fmt: skip
    callbacks: list[Any] = [evaluator]
    if progress:
        callbacks.append(ProgressBar(steps, evaluator))
    try:
        model.learn(total_timesteps=steps, callback=callbacks)
    finally:
        vec.close()
        eval_env.close()
    model_path = out / "model.zip"
    model.save(model_path)
    wall = time.perf_counter() - start

    points = evaluator.points
    hit = next((p for p in points if p.success_rate >= config.target_success), None)
    result = TrainResult(
        out=out,
        model_path=model_path,
        steps=int(model.num_timesteps),
        wall_time_s=round(wall, 3),
        train_time_s=round(wall - evaluator.eval_time_s, 3),
        final_success=points[-1].success_rate,
        steps_to_target=hit.steps if hit else None,
        time_to_target_s=hit.wall_time_s if hit else None,
        curve=[p.to_json() for p in points],
    )
    title = f"{algo} on {env_id} ({grounding}, {num_objects or '2-5'} objects, seed {seed})"
    plot_learning_curve(points, out / "learning_curve.png", title, config.target_success)
    (out / "train.json").write_text(json.dumps(_report(config, hyper, result), indent=2) + "\n")
    return result


def _report(config: TrainConfig, hyper: dict[str, Any], result: TrainResult) -> dict[str, Any]:
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
