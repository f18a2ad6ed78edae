"""The worker side of `planning_speed.py`: a process running the code of one tree (first on
its ``PYTHONPATH``) that answers measurement requests, one JSON line each way.

``plan`` workers import the planner and plan nothing before the first request, so each
cold plan, in a child forked per request, sees a fresh process; ``env`` workers build the
symbolic env on their first request and keep it across rounds.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import sys
import time
from typing import Any


def cpu(who: int = resource.RUSAGE_SELF) -> float:
    own = resource.getrusage(who)
    return own.ru_utime + own.ru_stime


def _plan(name: str) -> dict[str, Any]:
    """Plan a scene with a fresh `StatePlanner` in this process; its figures."""
    from utamp_gym.planning.methods import plan_scene
    from utamp_gym.planning.state_planner import StatePlanner
    from utamp_gym.suites import resolve_scene

    scene = resolve_scene(name)
    used = cpu() + cpu(resource.RUSAGE_CHILDREN)
    out = plan_scene(scene, "utamp2-gt", planner=StatePlanner("utamp2"))
    used = cpu() + cpu(resource.RUSAGE_CHILDREN) - used
    return {
        "s": out.planning_time_s,
        "cpu_s": used,
        "solved": out.solved,
        "length": out.plan_length,
        "domain": out.domain,
        "problem": out.problem,
    }


def _cold(name: str) -> dict[str, Any]:
    """`_plan` in a forked child: a fresh process state, imports done."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: plan, answer, leave without clean-up
        os.close(read)
        try:
            data = json.dumps(_plan(name)).encode()
        except BaseException as exc:  # the parent reports it
            data = json.dumps({"error": repr(exc)}).encode()
        with os.fdopen(write, "wb") as f:
            f.write(data)
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as f:
        data = f.read()
    os.waitpid(pid, 0)
    out = json.loads(data)
    if "error" in out:
        raise RuntimeError(f"cold plan of {name}: {out['error']}")
    return out


def _warm(name: str, repeats: int) -> dict[str, Any]:
    """`_plan` `repeats` times in this (long-lived) process: medians."""
    runs = [_plan(name) for _ in range(repeats)]
    return {
        "s": statistics.median(r["s"] for r in runs),
        "cpu_s": statistics.median(r["cpu_s"] for r in runs),
    }


class _Env:
    """The raw symbolic env of `benchmarks/env_throughput.py`, kept across rounds."""

    def __init__(self, suite: str) -> None:
        from utamp_gym.env.kitchen import UTampKitchenEnv

        self.env = UTampKitchenEnv(suite=suite, grounding="symbolic")
        self.run(2_000, 0)  # warm-up

    def run(self, steps: int, seed: int) -> dict[str, Any]:
        """Masked random steps (`env_throughput.run`): steps/s inside `env.step`."""
        import numpy as np

        draws = np.random.default_rng(seed).random(steps)
        _, info = self.env.reset(seed=seed)
        in_step, cpu = 0.0, time.process_time()
        for k in range(steps):
            valid = np.flatnonzero(info["action_mask"])
            action = valid[int(draws[k] * len(valid))] if len(valid) else np.int64(0)
            t = time.perf_counter()
            _, _, terminated, truncated, info = self.env.step(action)
            in_step += time.perf_counter() - t
            if terminated or truncated:
                _, info = self.env.reset()
        return {
            "steps_per_s": steps / in_step,
            "cpu_steps_per_s": steps / (time.process_time() - cpu),
        }


def worker(kind: str) -> None:
    """Serve measurements: one JSON request per stdin line, one JSON answer per stdout line.

    ``plan`` workers import the planner and plan nothing before the first request (the cold
    forks see a fresh process); ``env`` workers build the env on their first request."""
    import utamp_gym

    out = sys.stdout
    sys.stdout = sys.stderr  # nothing else may write to the answer stream
    if kind == "plan":
        import utamp_gym.planning.methods
        import utamp_gym.planning.state_planner
        import utamp_gym.suites
    env: _Env | None = None
    print(json.dumps({"ready": utamp_gym.__file__}), file=out, flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        if req["op"] == "cold":
            ans = _cold(req["scene"])
        elif req["op"] == "warm":
            ans = _warm(req["scene"], req["repeats"])
        else:
            env = env or _Env(req["suite"])
            ans = env.run(req["steps"], req["seed"])
        print(json.dumps(ans), file=out, flush=True)


__all__ = ["cpu", "worker"]
