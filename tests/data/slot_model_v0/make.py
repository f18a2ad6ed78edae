"""Write the goal-free slot model fixture (run with the code *before* goal conditioning):

    cd /work/main && python tests/data/slot_model_v0/make.py   # (at main 7ca5dc2)

A `SlotPolicy` in a MaskablePPO model on UTampKitchenProcedural-v0 (objects interface, width
8, pointer head, seed 0, untrained but with its weights perturbed so every layer matters),
saved as ``model.zip``; ``cases.npz`` holds 4 observations and masks of the env (seeds 0-3)
and the action-distribution logits and values that code computed for them. The test
(tests/test_slot_goals.py) loads the model with the current code and compares.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import torch as th
from sb3_contrib import MaskablePPO

from utamp_gym.env.registry import register_envs
from utamp_gym.rl.slots import SlotPolicy

HERE = Path(__file__).resolve().parent


def main() -> None:
    register_envs()
    th.manual_seed(0)
    env = gym.make("UTampKitchenProcedural-v0", grounding="symbolic", masks="geometric")
    model = MaskablePPO(SlotPolicy, env, seed=0, device="cpu", n_steps=64, batch_size=64,
                        policy_kwargs={"features_extractor_kwargs": {"d_model": 8},
                                       "head": "pointer"})  # fmt: skip
    with th.no_grad():
        for p in model.policy.parameters():
            p.add_(0.3 * th.randn_like(p))
    model.save(HERE / "model.zip")
    obs, masks = [], []
    for seed in range(4):
        o, info = env.reset(seed=seed)
        obs.append(o)
        masks.append(info["action_mask"])
    batch = {k: np.stack([o[k] for o in obs]) for k in obs[0]}
    policy = model.policy
    policy.set_training_mode(False)
    tensor, _ = policy.obs_to_tensor(batch)
    with th.no_grad():
        dist = policy.get_distribution(tensor, action_masks=np.stack(masks))
        logits = dist.distribution.logits.numpy()
        values = policy.predict_values(tensor).numpy()
    np.savez_compressed(HERE / "cases.npz", masks=np.stack(masks), logits=logits, values=values,
                        **{f"obs_{k}": v for k, v in batch.items()})  # fmt: skip


if __name__ == "__main__":
    main()
