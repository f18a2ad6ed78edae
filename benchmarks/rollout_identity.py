"""Seeded rollouts of every registered env id, recorded to JSON and compared (refactor check).

For each id of `utamp_gym.env.registry.env_ids()` and each grounding it runs `--episodes`
seeded episodes (``reset(seed=i)``) with a seeded policy that picks an applicable action
(``info["action_mask"]``) with probability 0.7 and any action otherwise (so failures and
their reasons occur too), capped at `--symbolic-steps` / `--physics-steps` macro actions.
In symbolic grounding it also runs the planner policy (`PlannerPolicy`, seeded) on the same
seeds until the episode ends. Every step's action, reward, failure reason, termination flags
and the info's outcome fields are recorded, with the final object poses rounded to 1e-6 m
(quaternions to 1e-6).

    python benchmarks/rollout_identity.py record OUT.json [--episodes 20] [--physics-steps 8]
    python benchmarks/rollout_identity.py compare A.json B.json   # exit 1 on any difference

It runs unchanged on older trees (``PYTHONPATH=/path/to/old/tree``), to record a baseline.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
import zlib
from pathlib import Path
from typing import Any

os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np

from utamp_gym.env.registry import env_ids, register_envs

try:  # the policy's home after issue 37; its old one before
    from utamp_gym.agents import PlannerPolicy
except ImportError:
    from utamp_gym.env.planner_policy import PlannerPolicy

ROUND = 6  # decimals of poses (1e-6 m)
P_MASKED = 0.7


def _plain(value: Any) -> Any:
    """JSON-able, deterministic form of an info value."""
    if isinstance(value, np.ndarray):
        if value.dtype == bool:
            return "".join("1" if v else "0" for v in value)
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in sorted(value.items())}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return round(float(value), ROUND)
    if isinstance(value, np.integer):
        return int(value)
    return value


def _step_record(action: int, reward: float, term: bool, trunc: bool, info: dict) -> dict:
    keep = ("action", "failure_reason", "macro_result", "unexpected_atoms", "anomalies",
            "fault", "is_success", "action_mask")  # fmt: skip
    return {
        "a": int(action),
        "reward": round(float(reward), ROUND),
        "terminated": bool(term),
        "truncated": bool(trunc),
        **{k: _plain(info.get(k)) for k in keep},
    }


def _final(env: gym.Env, obs: dict) -> dict:
    kitchen = env.unwrapped
    out: dict[str, Any] = {"scene": kitchen.scene.name, "true_atoms": kitchen.true_atoms()}
    if kitchen.options.grounding == "physics":
        backend = kitchen.backend
        out["poses"] = {n: _plain(p) for n, p in sorted(backend.object_poses().items())}
        out["robot"] = _plain(np.round(np.asarray(backend.joint_positions(), float), ROUND))
    if "object_poses" in obs:
        out["obs_poses"] = _plain(np.round(obs["object_poses"].astype(float), ROUND))
    return out


def random_episode(env: gym.Env, seed: int, env_id: str, max_steps: int) -> dict:
    """One episode of the seeded masked/unmasked random policy."""
    rng = np.random.default_rng([seed, zlib.crc32(env_id.encode())])
    obs, info = env.reset(seed=seed)
    steps = []
    n = int(env.action_space.n)
    for _ in range(max_steps):
        valid = np.flatnonzero(info["action_mask"])
        if len(valid) and rng.random() < P_MASKED:
            action = int(valid[rng.integers(len(valid))])
        else:
            action = int(rng.integers(n))
        obs, reward, term, trunc, info = env.step(action)
        steps.append(_step_record(action, reward, term, trunc, info))
        if term or trunc:
            break
    return {"seed": seed, "reset_scene": info["scene"], "steps": steps, "final": _final(env, obs)}


def planner_episode(env: gym.Env, seed: int, max_steps: int = 40) -> dict:
    """One episode of the seeded planner policy (ends at the goal, a give-up or the cap)."""
    policy = PlannerPolicy(env, "utamp2-gt", seed=seed)
    obs, info = env.reset(seed=seed)
    steps: list[dict] = []
    gave_up = ""
    for _ in range(max_steps):
        try:
            action = policy(obs, info)
        except Exception as exc:  # PlanningError: recorded, as the policy's outcome
            gave_up = f"{type(exc).__name__}: {exc}"
            break
        obs, reward, term, trunc, info = env.step(action)
        steps.append(_step_record(action, reward, term, trunc, info))
        if term or trunc:
            break
    return {"seed": seed, "steps": steps, "gave_up": gave_up, "final": _final(env, obs)}


def record(args: argparse.Namespace) -> None:
    register_envs()
    out: dict[str, Any] = {}
    for env_id in env_ids():
        for grounding in ("symbolic", "physics"):
            start = time.perf_counter()
            env = gym.make(env_id, grounding=grounding)
            cap = args.symbolic_steps if grounding == "symbolic" else args.physics_steps
            out[f"{env_id}/{grounding}/random"] = [
                random_episode(env, i, env_id, cap) for i in range(args.episodes)
            ]
            if grounding == "symbolic":
                out[f"{env_id}/{grounding}/planner"] = [
                    planner_episode(env, i) for i in range(args.episodes)
                ]
            env.close()
            print(f"{env_id} {grounding}: {time.perf_counter() - start:.1f} s", file=sys.stderr)
    Path(args.out).write_text(json.dumps(out, indent=1, sort_keys=True) + "\n")


def _diff(a: Any, b: Any, where: str, found: list[str]) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                found.append(f"{where}/{k}: only in {'B' if k not in a else 'A'}")
            else:
                _diff(a[k], b[k], f"{where}/{k}", found)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _diff(x, y, f"{where}[{i}]", found)
    elif a != b:
        found.append(f"{where}: {json.dumps(a)[:200]} != {json.dumps(b)[:200]}")


def compare(args: argparse.Namespace) -> int:
    a = json.loads(Path(args.a).read_text())
    b = json.loads(Path(args.b).read_text())
    found: list[str] = []
    _diff(a, b, "", found)
    for line in found[:100]:
        print(line)
    if found:
        print(f"{len(found)} difference(s)")
        return 1
    episodes = [e for v in a.values() if isinstance(v, list) for e in v if isinstance(e, dict)]
    n_steps = sum(len(e.get("steps", ())) for e in episodes)
    print(f"identical: {len(a)} groups, {len(episodes)} episodes, {n_steps} steps")
    return 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    rec = sub.add_parser("record", help="run the rollouts and write them to OUT")
    rec.add_argument("out")
    rec.add_argument("--episodes", type=int, default=20)
    rec.add_argument("--symbolic-steps", type=int, default=30)
    rec.add_argument("--physics-steps", type=int, default=8)
    cmp_ = sub.add_parser("compare", help="print the differences of two recordings")
    cmp_.add_argument("a")
    cmp_.add_argument("b")
    args = ap.parse_args()
    warnings.simplefilter("ignore", DeprecationWarning)
    if args.cmd == "record":
        record(args)
    else:
        sys.exit(compare(args))


if __name__ == "__main__":
    main()
