"""Env throughput: symbolic-grounding steps per second on one core, then physics grounding.

The process is pinned to one CPU and BLAS to one thread. Each run takes masked random actions
(`info["action_mask"]`, choice from a pre-drawn stream) and resets at episode ends, so the
numbers include mask computation, observations, infos and resets. "step" counts only the time
inside `env.step`; "loop" also counts the agent's choice and the resets. Rows: the raw env and
the `gym.make` env (with Gymnasium's order-enforcing, time-limit and passive-checker wrappers).

    python benchmarks/env_throughput.py [--steps 100000] [--all] [--physics-steps 10]
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time
from typing import Any

import gymnasium as gym
import numpy as np

from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.registry import env_ids, register_envs

TARGET = 20_000  # symbolic steps/s


def run(env: gym.Env, steps: int, seed: int = 0) -> tuple[float, float, int]:
    """(loop steps/s, step-only steps/s, episodes) of masked random actions."""
    draws = np.random.default_rng(seed).random(steps)
    _, info = env.reset(seed=seed)
    in_step, episodes = 0.0, 0
    start = time.perf_counter()
    for k in range(steps):
        valid = np.flatnonzero(info["action_mask"])
        action = valid[int(draws[k] * len(valid))] if len(valid) else np.int64(0)
        t = time.perf_counter()
        _, _, terminated, truncated, info = env.step(action)
        in_step += time.perf_counter() - t
        if terminated or truncated:
            episodes += 1
            _, info = env.reset()
    return steps / (time.perf_counter() - start), steps / in_step, episodes


def symbolic_rows(args: argparse.Namespace) -> list[tuple[str, dict[str, Any]]]:
    rows: list[tuple[str, dict[str, Any]]] = [(i, {}) for i in env_ids()]
    if args.all:
        rows += [
            ("UTampKitchen-v0", {"affordances": "noisy", "noise": 0.1}),
            ("UTampKitchen-v0", {"domain": "utamp1"}),
            ("UTampKitchen-v0", {"reward_shaping": True, "camera": True}),
        ]
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--all", action="store_true", help="also noisy, utamp1 and camera configs")
    ap.add_argument("--physics-steps", type=int, default=10, help="0 skips physics")
    args = ap.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    register_envs()

    print(f"symbolic grounding, {args.steps} masked random steps, one core (target {TARGET}/s)")
    print(f"{'env':24} {'options':36} {'wrapping':8} {'actions':>7} {'loop/s':>9} {'step/s':>9}")
    for env_id, kw in symbolic_rows(args):
        suite = gym.spec(env_id).kwargs["suite"]
        envs = {
            "raw": UTampKitchenEnv(suite=suite, grounding="symbolic", **kw),
            "make": gym.make(env_id, grounding="symbolic", **kw),
        }
        for label, env in envs.items():
            run(env, 2_000)  # warm-up
            loop, step, _ = run(env, args.steps)
            flag = "" if step >= TARGET or kw else "  BELOW TARGET"
            options = ", ".join(f"{k}={v}" for k, v in kw.items()) or "-"
            n = env.action_space.n
            print(f"{env_id:24} {options:36} {label:8} {n:>7} {loop:>9,.0f} {step:>9,.0f}{flag}")

    if args.physics_steps <= 0:
        return
    try:
        import utamp_gym.sim.backend  # noqa: F401
    except ImportError as exc:
        print(f"physics grounding: not available ({exc})")
        return
    env = gym.make("UTampKitchen-v0", num_objects=3)
    start = time.perf_counter()
    env.reset(seed=0)
    reset_s = time.perf_counter() - start
    loop, step, _ = run(env, args.physics_steps)
    print(f"physics grounding: reset {reset_s:.2f} s, {1 / step:.3f} s/step in env.step "
          f"({args.physics_steps} masked random steps, 3 objects)")  # fmt: skip
    env.close()


if __name__ == "__main__":
    main()
