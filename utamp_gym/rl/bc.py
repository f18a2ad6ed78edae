"""Behaviour cloning from planner demonstrations: the slot policy trained on a Minari dataset.

Why a short torch loop and not `imitation`: imitation 1.0.1 (the current release) pins
gymnasium 0.29 and stable-baselines3 2.2, and installing it would downgrade this project's
gymnasium 1.4 and SB3 2.9. The loss is what imitation's BC minimises for a discrete policy:
the negative log-likelihood of the demonstrated action under the masked policy (the mask the
demonstrator acted under, ``info["action_mask"]``), on minibatches, with Adam.

The policy is MaskablePPO's `utamp_gym.rl.slots.SlotPolicy` inside a `MaskablePPO` model, saved
with its `ModelMeta` like every trained agent: ``utamp eval --methods rl:PATH`` runs it, and
``utamp train --init-from PATH`` fine-tunes it with MaskablePPO. The demonstrations come from
``utamp demos`` (macro track, objects interface); only episodes that reached the goal are used.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.errors import UtampError
from utamp_gym.rl.callbacks import PeriodicEval, plot_learning_curve
from utamp_gym.rl.config import TrainResult
from utamp_gym.rl.envs import make_env
from utamp_gym.rl.runs import eval_episodes_of, model_meta, save_model
from utamp_gym.rl.slots import SlotPolicy

BC_DEFAULTS = {"learning_rate": 3e-4, "batch_size": 128, "epochs": 30, "eval_every_epochs": 5}


def open_demos(path: str | Path) -> Any:
    """The Minari dataset in folder `path` (the folder `utamp demos` printed, or its data/)."""
    from minari import MinariDataset

    path = Path(path)
    data = path / "data" if (path / "data").is_dir() else path
    if not (data / "metadata.json").is_file():
        raise UtampError(f"{path} is not a Minari dataset folder (no data/metadata.json)")
    return MinariDataset(data)


def demo_arrays(dataset: Any) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, int]:
    """(observations, actions, masks, env steps) of the successful episodes' steps."""
    obs: dict[str, list[np.ndarray]] = {}
    actions, masks, steps = [], [], 0
    for ep in dataset.iterate_episodes():
        if not (len(ep.actions) and ep.terminations[-1] and ep.rewards[-1] >= 1.0):
            continue
        n = len(ep.actions)
        for k, v in ep.observations.items():
            obs.setdefault(k, []).append(np.asarray(v[:n]))
        actions.append(np.asarray(ep.actions))
        masks.append(np.asarray(ep.infos["action_mask"][:n], bool))
        steps += n
    if not actions:
        raise UtampError("the dataset has no successful episode to learn from")
    return {k: np.concatenate(v) for k, v in obs.items()}, np.concatenate(actions), \
        np.concatenate(masks), steps  # fmt: skip


def clone(
    model: Any,
    dataset: Any,
    *,
    epochs: int,
    batch_size: int,
    learning_rate: float,
    seed: int,
    on_epoch: Any = None,
) -> dict[str, float]:
    """Fit `model.policy` to the demonstrations; ``on_epoch(epoch, loss)`` after each epoch.
    Returns the final mean loss and the demonstrations' size."""
    import torch as th

    obs, actions, masks, steps = demo_arrays(dataset)
    policy = model.policy
    optimizer = th.optim.Adam(policy.parameters(), lr=learning_rate)
    rng = np.random.default_rng(seed)
    n = len(actions)
    loss_value = first = float("nan")
    for epoch in range(1, epochs + 1):
        order = rng.permutation(n)
        total = 0.0
        policy.set_training_mode(True)
        for start in range(0, n, batch_size):
            idx = order[start : start + batch_size]
            batch = {k: th.as_tensor(v[idx]) for k, v in obs.items()}
            tensor, _ = policy.obs_to_tensor({k: v.numpy() for k, v in batch.items()})
            _, log_prob, _ = policy.evaluate_actions(
                tensor, th.as_tensor(actions[idx]), action_masks=masks[idx]
            )
            loss = -log_prob.mean()
            optimizer.zero_grad()
            loss.backward()
            th.nn.utils.clip_grad_norm_(policy.parameters(), 0.5)
            optimizer.step()
            total += float(loss.detach()) * len(idx)
        policy.set_training_mode(False)
        loss_value = total / n
        first = loss_value if epoch == 1 else first
        if on_epoch is not None:
            on_epoch(epoch, loss_value)
    return {"loss": loss_value, "first_epoch_loss": first, "transitions": float(n),
            "demo_steps": float(steps)}  # fmt: skip


def train_bc(config: Any, out: Path, *, progress: bool = False) -> Any:
    """Behaviour cloning of one seed (`utamp_gym.rl.train.train` with ``algo="bc"``): writes
    ``model.zip``, ``checkpoints/``, ``learning_curve.png`` and ``train.json`` as `train` does;
    the curve's ``steps`` are demonstration samples seen (epochs x transitions)."""
    import torch as th
    from sb3_contrib import MaskablePPO

    th.manual_seed(config.seed)
    start = time.perf_counter()
    hyper = {**BC_DEFAULTS, **config.hyperparams}
    env_kw = {"grounding": config.grounding, "num_objects": config.num_objects,
              "masks": config.masks, "interface": config.interface,
              **config.env_options}  # fmt: skip
    env = make_env(config.env_id, obs_keys=None, **env_kw)
    meta = model_meta(config, env)
    model = MaskablePPO(SlotPolicy, env, seed=config.seed, device="cpu")
    dataset = open_demos(config.demos)
    evaluator = PeriodicEval(env, eval_episodes_of(config), out, 1,
                             save=lambda m, p: save_model(m, p, meta))  # fmt: skip
    evaluator.init_callback(model)
    evaluator._start = start
    samples = {"seen": 0}
    size = len(demo_arrays(dataset)[1])

    def on_epoch(epoch: int, loss: float) -> None:
        samples["seen"] += size
        model.num_timesteps = evaluator.num_timesteps = samples["seen"]
        if epoch % int(hyper["eval_every_epochs"]) == 0 or epoch == int(hyper["epochs"]):
            evaluator.evaluate()

    fit = clone(model, dataset, epochs=int(hyper["epochs"]), batch_size=int(hyper["batch_size"]),
                learning_rate=float(hyper["learning_rate"]), seed=config.seed,
                on_epoch=on_epoch)  # fmt: skip
    env.close()
    path = out / "model.zip"
    save_model(model, path, meta)
    wall = time.perf_counter() - start
    points = evaluator.points
    hit = next((p for p in points if p.success_rate >= config.target_success), None)
    result = TrainResult(
        out=out, model_path=path, steps=int(fit["demo_steps"]), wall_time_s=round(wall, 3),
        train_time_s=round(wall - evaluator.eval_time_s, 3),
        final_success=points[-1].success_rate, steps_to_target=hit.steps if hit else None,
        time_to_target_s=hit.wall_time_s if hit else None, curve=[p.to_json() for p in points],
    )  # fmt: skip
    title = f"behaviour cloning on {config.env_id} ({config.demos}, seed {config.seed})"
    plot_learning_curve(points, out / "learning_curve.png", title, config.target_success)
    return result, {**hyper, "final_loss": fit["loss"], "first_epoch_loss": fit["first_epoch_loss"],
                    "transitions": fit["transitions"]}  # fmt: skip
