"""Planning speed: this code against an earlier commit and Fast Downward's driver, in one run.

The earlier commit (``--base``, default f68ae5a) is checked out with ``git worktree add
--detach`` into a temporary folder. Worker processes (this script with ``--worker``) run the
same venv, each with one tree first on ``PYTHONPATH``; every measurement alternates between
the two trees (ABBA...), so the load of a shared machine hits both alike. Four figures:

* **cold**: `plan_scene` (UTAMP-2-GT: affordances, problem, grounding, SAS, search) with a
  fresh `StatePlanner`, in a **fresh process**: the worker (imports done, nothing planned)
  forks a child per measurement, so no cache of any earlier plan is warm, as in a
  ``utamp plan`` process. Beside it **cold, warm process**: the earlier benchmark's
  definition (`benchmarks/planning.py --sections suite`: a fresh `StatePlanner` per call in
  one long-lived process, median of ``--repeats`` calls per scene).
* **driver**: ``fast-downward.py`` running the same search on the same PDDL files
  (`solve_with_driver`, as `benchmarks/planning.py` measures it); cold / driver.
* **process**: whole processes, ``utamp plan SCENE --json`` of each tree against
  ``fast-downward.py --alias lama-first domain.pddl problem.pddl``
  (`benchmarks/planning.py --sections process`).
* **env steps/s**: the raw symbolic `UTampKitchenEnv` (pick-place), masked random actions,
  steps per second inside `env.step` (`benchmarks/env_throughput.py`), in alternating rounds.

All on the five-object scenes of ``--suite``. Targets: cold median <= the base's and <= 0.15x
the driver; ``utamp plan`` <= 0.5x the driver; env steps/s >= the base's. Writes ``<out>.md``
(the table) and ``<out>.json`` (every measurement), with both commits and the command.

    python benchmarks/planning_speed.py [--base f68ae5a] [--suite pick-place] [--repeats 3]
        [--process-scenes 5] [--process-runs 5] [--env-rounds 20] [--env-steps 3000]
        [--out docs/results/planning_speed]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shlex
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from compare import Worker, base_worktree, git, med, rounded  # benchmarks/ is on sys.path
from planning_speed_report import VERSIONS, summarise, table
from planning_speed_worker import cpu, worker

ONE_THREAD = {"OMP_NUM_THREADS": "1"}  # the workers' environment
HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


# --------------------------------------------------------------------------- driver side
def _worker(label: str, tree: Path, kind: str) -> Worker:
    """A worker of `kind` (plan | env) running `tree`'s code, one thread."""
    return Worker(label, tree, Path(__file__), "--worker", kind, env=ONE_THREAD)


def wall_cpu(cmd: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float]:
    """(wall s, CPU s of the child) of one whole command."""
    c, t = cpu(resource.RUSAGE_CHILDREN), time.perf_counter()
    subprocess.run(cmd, env=env, cwd=cwd, check=True, capture_output=True)
    return time.perf_counter() - t, cpu(resource.RUSAGE_CHILDREN) - c


def bench_plans(
    workers: dict[str, Worker], names: list[str], repeats: int, tmp: Path
) -> list[dict[str, Any]]:
    """Cold (fresh process) and driver times per scene, then cold in a warm process (after
    every fresh-process plan: the workers have planned nothing until then)."""
    from utamp_gym.planning.fast_downward import DEFAULT_SEARCH, solve_with_driver

    rows = []
    for i, name in enumerate(names):
        row: dict[str, Any] = {"scene": name}
        order = VERSIONS if i % 2 == 0 else VERSIONS[::-1]
        cold: dict[str, list[dict[str, Any]]] = {v: [] for v in VERSIONS}
        for k in range(repeats):
            for v in order if k % 2 == 0 else order[::-1]:
                cold[v].append(workers[v].ask(op="cold", scene=name))
        for v in VERSIONS:
            row[v] = {
                "cold_s": med(r["s"] for r in cold[v]),
                "cold_cpu_s": med(r["cpu_s"] for r in cold[v]),
                "solved": cold[v][0]["solved"],
                "length": cold[v][0]["length"],
            }
        d, p = tmp / "domain.pddl", tmp / "problem.pddl"
        d.write_text(cold["this"][0]["domain"])
        p.write_text(cold["this"][0]["problem"])
        drv = []
        for _ in range(repeats):
            c = cpu(resource.RUSAGE_CHILDREN)
            res = solve_with_driver(d, p, search=DEFAULT_SEARCH)
            drv.append((res.planning_time_s, cpu(resource.RUSAGE_CHILDREN) - c))
        row["driver"] = {
            "s": med(w for w, _ in drv),
            "cpu_s": med(c for _, c in drv),
            "length": len(res.plan),
        }
        rows.append(row)
        print(
            f"{name}: cold this {1000 * row['this']['cold_s']:.1f} ms, base "
            f"{1000 * row['base']['cold_s']:.1f} ms; driver {1000 * row['driver']['s']:.1f} ms",
            flush=True,
        )
    for i, row in enumerate(rows):
        for v in VERSIONS if i % 2 == 0 else VERSIONS[::-1]:
            warm = workers[v].ask(op="warm", scene=row["scene"], repeats=repeats)
            row[v].update(warm_s=warm["s"], warm_cpu_s=warm["cpu_s"])
    print(
        "warm process: this "
        f"{1000 * med(r['this']['warm_s'] for r in rows):.1f} ms, base "
        f"{1000 * med(r['base']['warm_s'] for r in rows):.1f} ms",
        flush=True,
    )
    return rows


def bench_process(
    trees: dict[str, Path], names: list[str], runs: int, tmp: Path
) -> list[dict[str, Any]]:
    """Whole ``utamp plan`` processes of both trees and the driver, interleaved."""
    from utamp_gym.planning.fast_downward import downward_paths

    _, driver = downward_paths()
    utamp = Path(sys.executable).with_name("utamp")
    base_env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    envs = {v: dict(base_env, PYTHONPATH=str(trees[v])) for v in VERSIONS}
    envs["driver"] = base_env
    rows = []
    for name in names:
        out = tmp / name.replace("/", "-")
        ours = [str(utamp), "plan", name, "--json"]
        subprocess.run([*ours, "--out", str(out)], env=envs["this"], check=True,
                       capture_output=True)  # fmt: skip
        cmds = {v: ours for v in VERSIONS}
        cmds["driver"] = [sys.executable, str(driver), "--alias", "lama-first",
                          str(out / "domain.pddl"), str(out / "problem.pddl")]  # fmt: skip
        for key, cmd in cmds.items():  # warm-up (byte-code caches, page cache)
            subprocess.run(cmd, env=envs[key], cwd=out, check=True, capture_output=True)
        times: dict[str, list[tuple[float, float]]] = {k: [] for k in cmds}
        keys = list(cmds)
        for k in range(runs):
            for key in keys if k % 2 == 0 else keys[::-1]:
                times[key].append(wall_cpu(cmds[key], envs[key], out))
        row: dict[str, Any] = {"scene": name}
        for key, xs in times.items():
            row[key] = {"s": med(w for w, _ in xs), "cpu_s": med(c for _, c in xs)}
        rows.append(row)
        print(
            f"{name}: utamp plan this {1000 * row['this']['s']:.0f} ms, base "
            f"{1000 * row['base']['s']:.0f} ms, driver {1000 * row['driver']['s']:.0f} ms",
            flush=True,
        )
    return rows


def bench_env(workers: dict[str, Worker], suite: str, rounds: int, steps: int) -> list[dict]:
    """Symbolic env steps/s of both trees in alternating rounds (same seed per round)."""
    rows = []
    for k in range(rounds):
        row: dict[str, Any] = {"round": k}
        for v in VERSIONS if k % 2 == 0 else VERSIONS[::-1]:
            ans = workers[v].ask(op="env", suite=suite, steps=steps, seed=k)
            row[v], row[f"{v}_cpu"] = ans["steps_per_s"], ans["cpu_steps_per_s"]
        rows.append(row)
        print(f"env round {k}: this {row['this']:,.0f}/s, base {row['base']:,.0f}/s", flush=True)
    return rows


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", choices=("plan", "env"), help=argparse.SUPPRESS)
    ap.add_argument("--base", default="f68ae5a", help="earlier commit to compare with")
    ap.add_argument("--suite", default="pick-place")
    ap.add_argument("--stride", type=int, default=1, help="every k-th five-object scene")
    ap.add_argument("--repeats", type=int, default=3, help="plans per scene and tree")
    ap.add_argument("--process-scenes", type=int, default=5)
    ap.add_argument("--process-runs", type=int, default=5)
    ap.add_argument("--env-rounds", type=int, default=20)
    ap.add_argument("--env-steps", type=int, default=3_000)
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "planning_speed"))
    return ap


def main() -> None:
    args = build_parser().parse_args()
    if args.worker:
        worker(args.worker)
        return
    command = shlex.join(["python", "benchmarks/planning_speed.py", *sys.argv[1:]])

    # here, not at the top: a worker runs this file against the base tree
    from utamp_gym.provenance import commit
    from utamp_gym.suites import suite_scenes

    base = git("rev-parse", "--short", args.base)
    this = commit()  # as the footer records it (results files being written do not count)
    five = [s.name for s in suite_scenes(args.suite) if s.n_objects == 5]
    names = five[:: args.stride]
    procs = five[:: max(1, len(five) // args.process_scenes)][: args.process_scenes]
    load0 = os.getloadavg()[0]
    print(f"base {base} vs this {this}; {len(names)} scenes; load {load0:.1f}", flush=True)
    started = time.perf_counter()
    with base_worktree(base, "planning_speed_") as tree:
        tmp = tree.parent  # the run's scratch files sit beside the worktree
        trees = {"this": ROOT, "base": tree}
        workers: dict[str, Worker] = {}
        try:
            workers = {v: _worker(v, trees[v], "plan") for v in VERSIONS}
            plans = bench_plans(workers, names, args.repeats, Path(tmp))
            for w in workers.values():
                w.close()
            process = bench_process(trees, procs, args.process_runs, Path(tmp))
            workers = {v: _worker(v, trees[v], "env") for v in VERSIONS}
            env = bench_env(workers, args.suite, args.env_rounds, args.env_steps)
        finally:
            for w in workers.values():
                if w.proc.poll() is None:
                    w.close()
    elapsed = time.perf_counter() - started
    summary = summarise(plans, process, env)
    run = (
        f"One run, {elapsed / 60:.1f} min, load average {load0:.1f} at the start and "
        f"{os.getloadavg()[0]:.1f} at the end ({os.cpu_count()} cores)."
    )
    md = table(summary, base, this, len(names), len(procs), args, run, command)
    print("\n" + md)
    differ = summary["plan_length_differs_from_driver"]
    print(f"our plans as long as the driver's (same optimal search): {differ or 'all'}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text(md)
    report = {
        "commit": this,
        "command": command,
        "base": base,
        "load_average": [load0, os.getloadavg()[0]],
        "elapsed_s": elapsed,
        "summary": summary,
        "plans": plans,
        "process": process,
        "env": env,
    }
    out.with_suffix(".json").write_text(json.dumps(rounded(report), indent=1) + "\n")
    print(f"wrote {out.with_suffix('.md')}, {out.with_suffix('.json')}")


if __name__ == "__main__":
    main()
