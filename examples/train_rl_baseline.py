"""Reproduce the RL headline run: MaskablePPO on three-object pick-place scenes (symbolic).

    python examples/train_rl_baseline.py [--out out/rl/headline] [--steps 50000] [--seed 0]
        [--algo maskable-ppo] [--num-objects 3] [--envs 8] [--eval-objects 2 3 4 5]

Trains (writing model.zip, checkpoints/, learning_curve.png and train.json to --out), prints
the steps and wall time to 90 % evaluation success, then a success-vs-objects table of the
trained policy next to the Fast Downward planner (`PlannerPolicy`) on the same scenes.
"""

from __future__ import annotations

import argparse
import statistics
from typing import Any

import gymnasium as gym

from utamp_gym.env.planner_policy import PlannerPolicy
from utamp_gym.rl.policy import ALGOS, evaluate_rl, run_episodes
from utamp_gym.rl.train import train


def planner_rows(num_objects: int, seeds: list[int]) -> list[dict[str, Any]]:
    """The planner's episodes on every `num_objects`-object scene (same rows as evaluate_rl)."""
    env = gym.make("UTampKitchen-v0", grounding="symbolic", num_objects=num_objects)
    names = [s.name for s in env.unwrapped.scenes]
    rows = run_episodes(env, PlannerPolicy(env), [(n, s) for n in names for s in seeds])
    env.close()
    return rows


def summary(rows: list[dict[str, Any]]) -> str:
    success = sum(r["success"] for r in rows) / len(rows)
    steps = statistics.mean(r["steps"] for r in rows)
    ms = 1000 * statistics.mean(r["episode_time_s"] for r in rows)
    return f"{success:6.1%} {steps:6.1f} {ms:8.1f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/rl/headline")
    ap.add_argument("--algo", default="maskable-ppo", choices=ALGOS)
    ap.add_argument("--num-objects", type=int, default=3)
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--envs", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--eval-every", type=int, default=2_000)
    ap.add_argument("--eval-objects", type=int, nargs="*", default=[2, 3, 4, 5])
    args = ap.parse_args()

    result = train(
        algo=args.algo, num_objects=args.num_objects, steps=args.steps, n_envs=args.envs,
        seed=args.seed, out=args.out, eval_every=args.eval_every, eval_episodes=60,
    )  # fmt: skip
    print(f"trained {result.steps} steps in {result.wall_time_s:.1f} s "
          f"({result.train_time_s:.1f} s without evaluations); final success "
          f"{result.final_success:.1%}")  # fmt: skip
    if result.steps_to_target is not None:
        print(f">= 90 % success first at {result.steps_to_target} steps, "
              f"{result.time_to_target_s:.1f} s of training")  # fmt: skip
    if not args.eval_objects:
        return
    print(f"\n{'objects':>7} | {'RL success':>10} {'steps':>6} {'ms/ep':>8} | "
          f"{'planner':>7} {'steps':>6} {'ms/ep':>8}")  # fmt: skip
    for n in args.eval_objects:
        rl = evaluate_rl(result.model_path, num_objects=n, seeds=[0])
        plan = planner_rows(n, seeds=[0])
        print(f"{n:>7} | {summary(rl):>25} | {summary(plan)}   ({len(rl)} scenes)")


if __name__ == "__main__":
    main()
