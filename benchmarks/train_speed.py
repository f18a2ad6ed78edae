"""Training speed of `utamp train`'s default configurations: this code against an earlier
commit, side by side in one run.

The earlier commit (``--base``, default 3675150) is checked out with ``git worktree add`` into
a temporary folder. Every training run is a fresh process of this script (``--worker``) with
one tree first on ``PYTHONPATH``, calling `utamp_gym.rl.train.train` as ``utamp train`` does
(start-up included); the runs of the two trees alternate (ABBA...), so the load of a shared
machine hits both alike. Configurations (`CONFIGS`):

* ``grounded``: MaskablePPO with the MLP policy on UTampKitchen-v0 (``utamp train``'s
  defaults: grounded interface, affordance masks);
* ``objects``: MaskablePPO with the slot policy on UTampKitchenProcedural-v0 (objects
  interface, geometric masks: ``utamp train --env UTampKitchenProcedural-v0 --interface
  objects --masks geometric``).

Each run's evaluations (one at the end, `EVAL_EPISODES` episodes) are left out of its times;
before the rounds each tree builds each configuration's envs once (`warm_caches`), so that
both start with their caches on disk as any run after a machine's first does.
Inside `learn`, the wall time is split (self time, nested timers subtracted) into: env step
(``UTampKitchenEnv.step`` / ``reset`` less what follows), masks (``action_masks``, wherever
called), observation building (``_observation``), policy forward during rollouts (the
policy's ``forward`` and ``predict_values``), the update (``MaskablePPO.train``) and the
rest (SB3's rollout bookkeeping, vector-env wrappers, tensor conversion). Start-up is the
time from the call to the first rollout (env construction, action universes, the model).

Prints and writes ``<out>.md`` (the table, with ratios this / base) and ``<out>.json``.

    python benchmarks/train_speed.py [--base 3675150] [--rounds 2] [--configs grounded,objects]
        [--steps-grounded 8192] [--steps-objects 4096] [--out docs/results/train_speed]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from compare import base_worktree, git  # benchmarks/ is on sys.path when run

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TARGET = 5.0  # objects configuration: env steps per second, this / base
EVAL_EPISODES = 6
#: name -> `train` keyword arguments
CONFIGS: dict[str, dict[str, Any]] = {
    "grounded": {"env_id": "UTampKitchen-v0", "masks": "affordances", "interface": "grounded"},
    "objects": {
        "env_id": "UTampKitchenProcedural-v0", "masks": "geometric", "interface": "objects",
    },
}  # fmt: skip
PARTS = ("env step", "masks", "observation", "policy forward", "update", "other")


# --------------------------------------------------------------------------- worker
class Timers:
    """Self times of nested, named calls; nothing is counted inside an evaluation."""

    def __init__(self) -> None:
        self.total: dict[str, float] = dict.fromkeys(PARTS, 0.0)
        self.calls: dict[str, int] = dict.fromkeys(PARTS, 0)
        self.stack: list[list[float]] = []  # [start, time in timed children]
        self.evaluating = 0
        self.eval_s = 0.0

    def wrap(self, owner: Any, name: str, part: str) -> None:
        """Time ``owner.name`` (a class or an instance attribute) as `part`."""
        fn = getattr(owner, name, None)
        if fn is None:
            return

        def timed(*args: Any, **kwargs: Any) -> Any:
            if self.evaluating:
                return fn(*args, **kwargs)
            self.stack.append([time.perf_counter(), 0.0])
            try:
                return fn(*args, **kwargs)
            finally:
                start, children = self.stack.pop()
                elapsed = time.perf_counter() - start
                self.total[part] += elapsed - children
                self.calls[part] += 1
                if self.stack:
                    self.stack[-1][1] += elapsed

        setattr(owner, name, timed)

    def wrap_eval(self, owner: Any, name: str) -> None:
        fn = getattr(owner, name)

        def timed(*args: Any, **kwargs: Any) -> Any:
            self.evaluating += 1
            start = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.evaluating -= 1
                self.eval_s += time.perf_counter() - start

        setattr(owner, name, timed)


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    return own.ru_utime + own.ru_stime


def worker(config: str, steps: int, seed: int) -> dict[str, Any]:
    """One ``utamp train`` run of `config` in this process (the tree on `PYTHONPATH`)."""
    start, cpu0 = time.perf_counter(), _cpu()
    from sb3_contrib import MaskablePPO

    import utamp_gym
    from utamp_gym.env.kitchen import UTampKitchenEnv
    from utamp_gym.rl.callbacks import PeriodicEval
    from utamp_gym.rl.train import train

    timers = Timers()
    for name, part in (("step", "env step"), ("reset", "env step"),
                       ("action_masks", "masks"), ("_observation", "observation")):  # fmt: skip
        timers.wrap(UTampKitchenEnv, name, part)
    timers.wrap(MaskablePPO, "train", "update")
    timers.wrap_eval(PeriodicEval, "evaluate")
    marks: dict[str, float] = {}
    setup: Callable[..., Any] = MaskablePPO._setup_model

    def setup_model(model: Any) -> None:
        setup(model)
        for name in ("forward", "predict_values"):
            timers.wrap(model.policy, name, "policy forward")

    MaskablePPO._setup_model = setup_model  # type: ignore[method-assign]
    learn = MaskablePPO.learn

    def timed_learn(model: Any, *args: Any, **kwargs: Any) -> Any:
        marks["learn"] = time.perf_counter()
        try:
            return learn(model, *args, **kwargs)
        finally:
            marks["learned"] = time.perf_counter()

    MaskablePPO.learn = timed_learn  # type: ignore[method-assign]
    imported = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="train_speed_") as out:
        result = train(
            **CONFIGS[config], steps=steps, n_envs=8, seed=seed, out=out, eval_every=steps,
            eval_episodes=EVAL_EPISODES, progress=False,
        )  # fmt: skip
    end = time.perf_counter()
    learn_s = marks["learned"] - marks["learn"] - timers.eval_s
    parts = dict(timers.total)
    parts["other"] = learn_s - sum(v for k, v in parts.items() if k != "other")
    return {
        "tree": str(Path(utamp_gym.__file__).resolve().parent.parent),
        "config": config,
        "steps": int(result.steps),
        "import_s": imported - start,
        "startup_s": marks["learn"] - imported,
        "learn_s": learn_s,
        "command_s": end - imported - timers.eval_s,
        "eval_s": timers.eval_s,
        "cpu_s": _cpu() - cpu0,
        "parts_s": parts,
        "calls": timers.calls,
        "final_success": result.final_success,
    }


# --------------------------------------------------------------------------- driver
def run_worker(tree: Path, config: str, steps: int, seed: int) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=str(tree))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", config,
           "--steps", str(steps), "--seed", str(seed)]  # fmt: skip
    proc = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{tree} {config}: worker failed\n{proc.stderr[-3000:]}")
    row = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(row["tree"]).resolve() == tree.resolve():
        raise RuntimeError(f"{config}: imported utamp_gym from {row['tree']}, not {tree}")
    return row


def warm_caches(tree: Path, config: str) -> None:
    """Build `config`'s envs once in a process of `tree`: whatever a tree keeps on disk (the
    procedural splits' scenes; this code's stored action universes) is then there for every
    timed run, as for every run after the first on a machine."""
    opts = {k: v for k, v in CONFIGS[config].items() if k != "env_id"}
    code = (
        "import gymnasium as gym; from utamp_gym.env.registry import register_envs; "
        f"register_envs(); gym.make({CONFIGS[config]['env_id']!r}, grounding='symbolic', "
        f"**{opts!r}); gym.make({CONFIGS[config]['env_id']!r}, grounding='symbolic')"
    )
    env = dict(os.environ, PYTHONPATH=str(tree))
    subprocess.run([sys.executable, "-c", code], cwd=tree, env=env, check=True)


def summarise(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per configuration and version: medians over the rounds, and ratios this / base."""
    out = []
    for config in dict.fromkeys(r["config"] for r in rows):
        entry: dict[str, Any] = {"config": config}
        for v in ("base", "this"):
            mine = [r for r in rows if r["config"] == config and r["version"] == v]
            steps = mine[0]["steps"]
            med = lambda key, mine=mine: statistics.median(r[key] for r in mine)  # noqa: E731
            entry[v] = {
                "runs": len(mine),
                "steps": steps,
                "steps_per_s": steps / med("learn_s"),
                "command_steps_per_s": steps / med("command_s"),
                "startup_s": med("startup_s"),
                "learn_s": med("learn_s"),
                "ms_per_1000": {
                    p: 1e6 * statistics.median(r["parts_s"][p] for r in mine) / steps for p in PARTS
                },
            }
        entry["ratio"] = {
            k: entry["this"][k] / entry["base"][k] for k in ("steps_per_s", "command_steps_per_s")
        }
        out.append(entry)
    return out


def table(summary: list[dict[str, Any]], base: str, this: str, run: str) -> str:
    head = " | ".join(f"{p} (ms / 1k steps)" for p in PARTS)
    lines = [
        f"| configuration | version | env steps / s (training) | ratio | env steps / s "
        f"(whole command) | ratio | start-up s | {head} |",
        "|---|---|---|---|---|---|---|" + "---|" * len(PARTS),
    ]
    for s in summary:
        for v, label in (("base", f"base `{base}`"), ("this", f"this `{this}`")):
            e = s[v]
            ratio = ("", "") if v == "base" else (
                f"**{s['ratio']['steps_per_s']:.2f}×**",
                f"**{s['ratio']['command_steps_per_s']:.2f}×**",
            )  # fmt: skip
            parts = " | ".join(f"{e['ms_per_1000'][p]:,.0f}" for p in PARTS)
            lines.append(
                f"| {s['config']} ({e['steps']:,} steps) | {label} | {e['steps_per_s']:,.0f} "
                f"| {ratio[0]} | {e['command_steps_per_s']:,.0f} | {ratio[1]} "
                f"| {e['startup_s']:.1f} | {parts} |"
            )
    lines.append("")
    lines.append(
        "Medians over the rounds; training = inside `learn`, whole command = from the call of "
        "`train` (after imports) to its return, start-up included; both leave out the "
        "evaluation at the end. Before the rounds, each tree built each configuration's envs "
        "once (its caches on disk warm, as for any run after a machine's first). "
        f"{run} Generated by `benchmarks/train_speed.py`."
    )
    return "\n".join(lines) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check the command a results file recorded)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", choices=tuple(CONFIGS), help=argparse.SUPPRESS)
    ap.add_argument("--steps", type=int, default=4096, help=argparse.SUPPRESS)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--base", default="3675150", help="earlier commit to compare with")
    ap.add_argument("--rounds", type=int, default=2, help="runs per version and configuration")
    ap.add_argument("--configs", default="grounded,objects")
    ap.add_argument("--steps-grounded", type=int, default=8192)
    ap.add_argument("--steps-objects", type=int, default=4096)
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "train_speed"))
    return ap


def main() -> None:
    args = build_parser().parse_args()
    if args.worker:
        row = worker(args.worker, args.steps, args.seed)
        print(json.dumps(row))
        return
    # here, not at the top: a worker runs this file against the base tree, which has no
    # utamp_gym.provenance
    from utamp_gym.provenance import commit, write_json, write_markdown

    base = git("rev-parse", "--short", args.base)
    this = commit()  # the provenance of what this run writes: the code as it is now
    configs = args.configs.split(",")
    steps = {"grounded": args.steps_grounded, "objects": args.steps_objects}
    load0 = os.getloadavg()
    print(f"base {base} vs this {this}; load {load0[0]:.1f}", flush=True)
    rows: list[dict[str, Any]] = []
    started = time.perf_counter()
    with base_worktree(base, "train_speed_") as tree:
        trees = {"this": ROOT, "base": tree}
        for t in trees.values():  # warm the caches on disk of each tree alike
            for config in configs:
                warm_caches(t, config)
        for k in range(args.rounds):
            for config in configs:
                order = ("this", "base") if k % 2 == 0 else ("base", "this")
                for v in order:
                    r = run_worker(trees[v], config, steps[config], args.seed)
                    rows.append({**r, "version": v})
                    print(
                        f"round {k} {config} {v}: {r['steps'] / r['learn_s']:.0f} steps/s "
                        f"training, start-up {r['startup_s']:.1f} s, "
                        + ", ".join(f"{p} {s:.1f} s" for p, s in r["parts_s"].items()),
                        flush=True,
                    )
    load1 = os.getloadavg()
    summary = summarise(rows)
    run = (
        f"Command: `python benchmarks/train_speed.py --rounds {args.rounds} --configs "
        f"{args.configs} --steps-grounded {args.steps_grounded} --steps-objects "
        f"{args.steps_objects}`; 8 envs, seed {args.seed}, symbolic grounding, "
        f"{time.perf_counter() - started:.0f} s on a shared {os.cpu_count()}-core machine, "
        f"load average {load0[0]:.1f} at the start and {load1[0]:.1f} at the end."
    )
    text = table(summary, base, this, run)
    print(text)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_markdown(out.with_suffix(".md"), text)
    data = {"base": base, "this": this, "summary": summary, "runs": rows, "run": run}
    write_json(out.with_suffix(".json"), data, indent=1)
    if "objects" in configs:
        q = next(s for s in summary if s["config"] == "objects")["ratio"]["steps_per_s"]
        print(f"objects configuration: {q:.2f}x the base's env steps/s (target {TARGET:.0f}x)")


if __name__ == "__main__":
    main()
