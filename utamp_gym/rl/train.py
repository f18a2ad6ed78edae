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

Mask modes (``masks``, the env option): "affordances" shows the agent the U-TAMP-2
precondition under ground-truth affordances (the planner's knowledge); "geometric" only the
object-centric preconditions, with the symbolic outcome model rejecting what the ground truth
forbids; "none" every action of the scene. MaskablePPO trains with the mode's masks; PPO and
DQN never see masks in training (evaluation applies the mode's mask unless ``eval_masks`` is
False).

Outputs in `out`: ``model.zip`` (final), ``checkpoints/step_<n>.zip`` (at every
evaluation), ``learning_curve.png`` and ``train.json`` (config, steps, wall times, curve).
Every zip carries its `ModelMeta` (env id, masks, observation keys, space sizes), so
``utamp eval --methods rl:PATH`` rebuilds its env. The run's configuration is
`utamp_gym.rl.config`, its files `utamp_gym.rl.runs`; several seeds, `utamp_gym.rl.seeds`.
"""

from __future__ import annotations

import functools
import json
import sys
import time
from pathlib import Path
from typing import Any

from utamp_gym.rl.bc import train_bc
from utamp_gym.rl.callbacks import PeriodicEval, ProgressBar, plot_learning_curve
from utamp_gym.rl.config import TrainConfig, TrainResult, default_hyperparams
from utamp_gym.rl.envs import make_env, make_vec_env
from utamp_gym.rl.policies import POLICY_CLASSES
from utamp_gym.rl.policy import algo_class
from utamp_gym.rl.runs import eval_episodes_of, model_meta, report, save_model
from utamp_gym.rl.slots import SlotPolicy


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

    `options` are the other `TrainConfig` fields (``masks``, ``eval_masks``, ``target_success``,
    ``stop_at_target``, ``reward_shaping``, ``terminate_on_failure``, ``obs_keys``,
    ``hyperparams``). Physics grounding trains in ``SubprocVecEnv`` workers.
    """
    import torch
    from stable_baselines3.common.logger import HumanOutputFormat, Logger

    config = TrainConfig(
        env_id=env_id, algo=algo, grounding=grounding, num_objects=num_objects, steps=steps,
        n_envs=n_envs, seed=seed, eval_every=eval_every, eval_episodes=eval_episodes,
        **options,
    )  # fmt: skip
    torch.set_num_threads(1)
    out = Path(out)
    (out / "checkpoints").mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    if algo == "bc":
        result, hyper = train_bc(config, out)
        (out / "train.json").write_text(json.dumps(report(config, hyper, result), indent=2) + "\n")
        return result

    env_kw: dict[str, Any] = {
        "grounding": grounding,
        "num_objects": num_objects,
        "masks": config.masks,
        "interface": config.interface,
        **config.env_options,
    }
    vec = make_vec_env(
        env_id, n_envs, seed=seed, subproc=grounding == "physics", obs_keys=config.obs_keys,
        reward_shaping=config.reward_shaping, terminate_on_failure=config.terminate_on_failure,
        **env_kw,
    )  # fmt: skip
    eval_env = make_env(env_id, obs_keys=None, **env_kw)
    meta = model_meta(config, eval_env)
    save = functools.partial(save_model, meta=meta)
    hyper = {**default_hyperparams(algo, n_envs, config.interface), **config.hyperparams}
    start_from = None
    if config.init_from:  # fine-tuning: the saved policy's network, then its weights
        start_from = algo_class(algo).load(config.init_from, device="cpu")
        if "policy_kwargs" not in config.hyperparams:
            hyper["policy_kwargs"] = dict(start_from.policy_kwargs)
    policy_class = POLICY_CLASSES[algo]
    if config.interface == "objects":
        policy_class = SlotPolicy
    model = algo_class(algo)(policy_class, vec, seed=seed, verbose=verbose, **hyper)
    # given no logger, SB3 makes an empty /tmp/SB3-<time> folder per run: log to stdout only
    model.set_logger(Logger(None, [HumanOutputFormat(sys.stdout)] if verbose else []))
    if start_from is not None:  # fine-tuning: start from a saved policy (e.g. behaviour cloning)
        model.policy.load_state_dict(start_from.policy.state_dict())
    evaluator = PeriodicEval(
        eval_env, eval_episodes_of(config), out, eval_every, save=save,
        masks=config.eval_masks, stop_at=config.target_success if config.stop_at_target else None,
        plateau=config.stop_at_plateau, time_limit_s=config.time_limit_s,
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
    save(model, model_path)
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
    title = (
        f"{algo}, masks {config.masks}, on {env_id} ({grounding}, {num_objects or '2-5'} "
        f"objects, seed {seed})"
    )
    plot_learning_curve(points, out / "learning_curve.png", title, config.target_success)
    (out / "train.json").write_text(json.dumps(report(config, hyper, result), indent=2) + "\n")
    return result
