"""Env loop speed: this tree against an earlier commit, side by side in one run (issue 37).

The earlier commit (``--base``, default 2c0b0d1, the commit before the one-loop refactor) is
checked out as a detached worktree (`compare.base_worktree`). Each round runs one worker
process per tree (this script with ``--worker``, the tree first on ``PYTHONPATH``), in the
order this, base, base, this, ... so the load of a shared machine hits both alike. A worker
measures, in one process:

* symbolic env steps/s: `--steps` masked random steps (an applicable action drawn from a
  pre-drawn stream, resets at episode ends) in a raw `UTampKitchenEnv` of every registered
  id, counting only the CPU time of this process inside ``env.step`` (steadier than wall
  time on a shared machine);
* physics episode wall time, on `--scenes`, seed 0, at the default pose noise: open loop
  (`run_episode`, ``utamp run SCENE``: UTAMP-2-GT planned, then played; on this tree
  through the env, on the base by `sim/execute.py`'s own loop) and closed loop
  (`run_closed_loop`, the planner policy acting in the physics env, ``--closed-loop``),
  after one untimed open-loop episode (the first of a process loads the planner, the
  simulator's assets and the env's action universe).

It prints the medians over the rounds per tree and the ratios this / base (target: steps/s
>= 0.95x, wall time <= 1.05x), and writes ``<out>.md`` and ``<out>.json``.

    python benchmarks/loop_speed.py [--base 2c0b0d1] [--rounds 3] [--steps 20000]
        [--scenes pick-place/003,sliding/003] [--out docs/results/loop_speed]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from compare import base_worktree, git  # benchmarks/ is on sys.path when run

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TOLERANCE = 0.05


# --------------------------------------------------------------------------- worker
def _cpu() -> float:
    """CPU seconds of this process and its finished children (the planner's subprocesses)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _steps_per_s(env_id: str, steps: int, seed: int = 0) -> float:
    import gymnasium as gym
    import numpy as np

    from utamp_gym.env.kitchen import UTampKitchenEnv

    kwargs = dict(gym.spec(env_id).kwargs)
    env = UTampKitchenEnv(**{**kwargs, "grounding": "symbolic"})
    draws = np.random.default_rng(seed).random(steps + 2_000)
    _, info = env.reset(seed=seed)
    inside = 0.0
    for k in range(steps + 2_000):  # the first 2000: warm-up (caches), not timed
        valid = np.flatnonzero(info["action_mask"])
        action = valid[int(draws[k] * len(valid))] if len(valid) else np.int64(0)
        t = time.process_time()
        _, _, terminated, truncated, info = env.step(action)
        if k >= 2_000:
            inside += time.process_time() - t
        if terminated or truncated:
            _, info = env.reset()
    return steps / inside


def worker(steps: int, scenes: list[str]) -> None:
    from utamp_gym.env.registry import env_ids, register_envs
    from utamp_gym.eval.closed_loop import run_closed_loop

    try:  # this tree; the base's runner was `sim/execute.py`
        from utamp_gym.agents.runs import run_episode
    except ImportError:
        from utamp_gym.sim.execute import run_episode

    register_envs()
    out: dict[str, Any] = {"steps_per_s": {}, "episode_s": {}, "episode_cpu_s": {}, "success": {}}
    for env_id in env_ids():
        out["steps_per_s"][env_id] = _steps_per_s(env_id, steps)
    run_episode(scenes[0], seed=1)  # warm-up: the first episode of a process loads caches
    for scene in scenes:
        start, cpu = time.perf_counter(), _cpu()
        ep = run_episode(scene, seed=0)
        out["episode_s"][f"open loop {scene}"] = time.perf_counter() - start
        out["episode_cpu_s"][f"open loop {scene}"] = _cpu() - cpu
        out["success"][f"open loop {scene}"] = [ep.success, ep.final_stack, ep.object_poses]
        start, cpu = time.perf_counter(), _cpu()
        result = run_closed_loop(scene, "utamp2-gt", seed=0, grounding="physics")
        out["episode_s"][f"closed loop {scene}"] = time.perf_counter() - start
        out["episode_cpu_s"][f"closed loop {scene}"] = _cpu() - cpu
        out["success"][f"closed loop {scene}"] = [result.success, list(result.actions)]
    print(json.dumps(out))


# --------------------------------------------------------------------------- driver
def _run(tree: Path, steps: int, scenes: list[str]) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, str(HERE / "loop_speed.py"), "--worker", "--steps", str(steps)]
    cmd += ["--scenes", ",".join(scenes)]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def table(summary: dict[str, Any], base: str, this: str) -> str:
    lines = [
        f"# Env loop speed: this ({this}) vs base ({base})",
        "",
        f"Medians over {summary['rounds']} interleaved rounds. Target: symbolic steps/s at "
        f"least {1 - TOLERANCE:.2f}x the base's, physics episode wall time at most "
        f"{1 + TOLERANCE:.2f}x. CPU time (this process and the planner's) beside wall time: "
        f"on a shared machine (load {summary['load'][0]:.1f} at the end) it is the steadier "
        "measure.",
        "",
        "| measure | case | base | this | this / base |",
        "|---|---|---:|---:|---:|",
    ]
    for key, unit, fmt in (("steps_per_s", "symbolic steps/s", ",.0f"),
                           ("episode_s", "physics episode wall s", ".2f"),
                           ("episode_cpu_s", "physics episode CPU s", ".2f")):  # fmt: skip
        for case, (b, t) in summary[key].items():
            lines.append(f"| {unit} | {case} | {b:{fmt}} | {t:{fmt}} | {t / b:.3f} |")
    same = "same" if summary["same_outcomes"] else "DIFFERENT"
    lines += [
        "",
        f"Outcomes of both trees (open loop: success, final tower and poses; closed loop: "
        f"success and actions): {same}.",
        "",
    ]
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    """The options (`tests/test_results_provenance.py` checks recorded commands against it)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="2c0b0d1")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--scenes", default="pick-place/003,sliding/003")
    ap.add_argument("--out", default=str(ROOT / "docs/results/loop_speed"))
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    return ap


def main() -> None:
    args = build_parser().parse_args()
    scenes = args.scenes.split(",")
    if args.worker:
        worker(args.steps, scenes)
        return
    # imported here, not at the top: a worker runs this file on the base commit's tree
    from utamp_gym.provenance import commit, write_json, write_markdown

    this = commit()
    base = git("rev-parse", "--short", args.base)
    runs: dict[str, list[dict[str, Any]]] = {"this": [], "base": []}
    with base_worktree(base, "loop_speed_") as tree:
        trees = {"this": ROOT, "base": tree}
        for r in range(args.rounds):
            for v in ("this", "base") if r % 2 == 0 else ("base", "this"):
                runs[v].append(_run(trees[v], args.steps, scenes))
                print(f"round {r} {v}: {json.dumps(runs[v][-1]['episode_s'])}", flush=True)
    summary: dict[str, Any] = {
        "rounds": args.rounds, "load": os.getloadavg(), "steps_per_s": {}, "episode_s": {},
        "episode_cpu_s": {},
    }  # fmt: skip
    for key in ("steps_per_s", "episode_s", "episode_cpu_s"):
        for case in runs["this"][0][key]:
            b = statistics.median(x[key][case] for x in runs["base"])
            t = statistics.median(x[key][case] for x in runs["this"])
            summary[key][case] = (b, t)
    summary["same_outcomes"] = all(
        x["success"] == runs["base"][0]["success"] for x in runs["this"] + runs["base"]
    )
    text = table(summary, base, this)
    print(text)
    out = Path(args.out)
    write_json(out.with_suffix(".json"), {"base": base, "this": this, **summary, "runs": runs})
    write_markdown(out.with_suffix(".md"), text)


if __name__ == "__main__":
    main()
