"""A random agent that only picks applicable actions (the env's action mask).

    python examples/random_masked_agent.py [--env UTampKitchen-v0] [--episodes 5]
        [--grounding symbolic] [--seed 0] [--num-objects N]

Prints each episode's scene, length, return and outcome. With ``--grounding physics`` every
macro action is simulated (slow, needs the MuJoCo backend).
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

from utamp_gym.env.registry import env_ids, register_envs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="UTampKitchen-v0", choices=env_ids())
    ap.add_argument("--episodes", type=int, default=5)
    ap.add_argument("--grounding", default="symbolic", choices=("symbolic", "physics"))
    ap.add_argument("--num-objects", type=int, default=None)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    register_envs()
    env = gym.make(args.env, grounding=args.grounding, num_objects=args.num_objects)
    rng = np.random.default_rng(args.seed)
    _, info = env.reset(seed=args.seed)
    for episode in range(args.episodes):
        ret, steps, done = 0.0, 0, False
        while not done:
            valid = np.flatnonzero(info["action_mask"])
            action = rng.choice(valid) if valid.size else 0  # no valid action: a dead end
            _, reward, terminated, truncated, info = env.step(action)
            ret, steps, done = ret + float(reward), steps + 1, terminated or truncated
        outcome = "goal" if ret >= 1.0 else ("truncated" if truncated else "dead end")
        print(f"episode {episode}: scene {info['scene']}, {steps} steps, return {ret:.2f}, "
              f"{outcome}")  # fmt: skip
        _, info = env.reset()
    env.close()


if __name__ == "__main__":
    main()
