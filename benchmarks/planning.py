"""Planning benchmark: our planner against Fast Downward's own driver, in one run.

Sections (``--sections``, default all but ``policy``):

* ``suite``: per object count, for UTAMP-2-GT (and UTAMP-1 on every ``--utamp1-stride``-th
  scene): the **cold** time (`plan_scene` with a fresh `StatePlanner`: affordances, problem,
  grounding, SAS, search), the **replan** time (the same planner from the state after the
  plan's first step: a cache hit, so only the initial state is written) and the time of
  ``fast-downward.py`` running the same search on the same PDDL files; medians and ratios.
* ``process``: whole processes on the same files: ``utamp plan SCENE --json`` against
  ``fast-downward.py --alias lama-first domain.pddl problem.pddl``.
* ``search``: the optimal search configurations side by side (replans of five-object
  UTAMP-2-GT tasks, five-object UTAMP-1 tasks, noisy-affordance tasks, some unsolvable).
* ``crosscheck``: on every suite scene, our grounder + SAS writer and Fast Downward's own
  translator give plans of equal length (both optimal); mismatches are listed.
* ``policy``: the `PlannerPolicy`'s planning time per five-object symbolic episode. It uses
  only APIs that predate `StatePlanner`, so ``PYTHONPATH=<old checkout>`` measures "before".

Times are wall-clock medians (what a caller waits), with CPU-time medians (process and
children) beside them: on a shared machine the CPU figures are the steadier ones.

    python benchmarks/planning.py [--sections suite,process,search,crosscheck,policy]
        [--suite pick-place] [--stride 1] [--utamp1-stride 6] [--repeats 3]
        [--process-scenes 5] [--process-runs 5] [--search astar-blind] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from compare import cpu_s, med  # benchmarks/ is on sys.path when run

SECTIONS = ("suite", "process", "search", "crosscheck", "policy")


def timed(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, float, float]:
    """(result, wall s, CPU s) of one call ``fn(*args, **kwargs)``."""
    c, t = cpu_s(), time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t, cpu_s() - c


def ms(x: float) -> str:
    return f"{x * 1000:.1f}"


# --------------------------------------------------------------------------- suite
def successor_args(outcome: Any, steps: int = 1) -> tuple[Any, ...]:
    """`StatePlanner.plan` arguments for the state after the first `steps` plan steps."""
    from utamp_gym.planning.state_planner import problem_atoms
    from utamp_gym.symbolic.pddl import parse_domain, parse_plan, parse_problem
    from utamp_gym.symbolic.validate import validate_plan

    domain, problem = parse_domain(outcome.domain), parse_problem(outcome.problem)
    objects, static, _, goal = problem_atoms(domain, problem)
    done = validate_plan(domain, problem, parse_plan("\n".join(outcome.plan[:steps])))
    fluent = domain.fluent_predicates()
    state = [str(a) for a in done.final_state if a.predicate in fluent]
    return objects, static, state, goal


def bench_suite(args: argparse.Namespace) -> list[dict[str, Any]]:
    from utamp_gym.planning.fast_downward import solve_with_driver
    from utamp_gym.planning.methods import method_spec, plan_scene
    from utamp_gym.planning.state_planner import StatePlanner
    from utamp_gym.suites import suite_scenes

    rows = []
    scenes = suite_scenes(args.suite)[:: args.stride]
    with tempfile.TemporaryDirectory() as tmp:
        for k, scene in enumerate(scenes):
            methods = ["utamp2-gt"] + (["utamp1"] if k % args.utamp1_stride == 0 else [])
            for method in methods:
                domain = method_spec(method).domain
                cold_w, cold_c = [], []
                out, planner = None, None
                for _ in range(args.repeats):
                    planner = StatePlanner(domain, search=args.search, timeout=args.timeout)
                    out, _, c = timed(
                        plan_scene, scene, method, planner=planner, timeout=args.timeout
                    )
                    cold_w.append(out.planning_time_s)
                    cold_c.append(c)
                assert out is not None and planner is not None
                row: dict[str, Any] = {
                    "scene": scene.name,
                    "n": scene.n_objects,
                    "method": method,
                    "solved": out.solved,
                    "plan_length": out.plan_length,
                    "cold_s": med(cold_w),
                    "cold_cpu_s": med(cold_c),
                }
                if out.solved and out.plan_length > 1:
                    plan_args = successor_args(out)
                    before = planner.cache_info()
                    rep_w, rep_c = [], []
                    for _ in range(args.repeats):
                        res, w, c = timed(planner.plan, *plan_args)
                        rep_w.append(w)
                        rep_c.append(c)
                    after = planner.cache_info()
                    row.update(
                        replan_s=med(rep_w),
                        replan_cpu_s=med(rep_c),
                        replan_hit=after.groundings == before.groundings,
                        replan_length=len(res.plan),
                    )
                d, p = Path(tmp, "domain.pddl"), Path(tmp, "problem.pddl")
                d.write_text(out.domain)
                p.write_text(out.problem)
                drv_w, drv_c = [], []
                for _ in range(args.repeats):
                    drv, w, c = timed(
                        solve_with_driver, d, p, search=args.search, timeout=args.timeout
                    )
                    drv_w.append(drv.planning_time_s)
                    drv_c.append(c)
                row.update(
                    driver_s=med(drv_w), driver_cpu_s=med(drv_c), driver_length=len(drv.plan)
                )
                rows.append(row)
                print(
                    f"{scene.name} {method:9s} cold {ms(row['cold_s'])} ms, replan "
                    f"{ms(row.get('replan_s', float('nan')))} ms, driver {ms(row['driver_s'])} ms",
                    flush=True,
                )
    print(
        f"\n## Planning time per object count ({args.suite}, search {args.search}, "
        f"medians of {args.repeats} repeats per scene, then over scenes; ms)\n"
    )
    print(
        "| method | n | scenes | solved | cold | replan | FD driver | cold / driver "
        "| replan / driver | cold CPU | replan CPU | driver CPU | cold CPU / driver CPU |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for method in ("utamp2-gt", "utamp1"):
        for n in sorted({r["n"] for r in rows}):
            sel = [r for r in rows if r["method"] == method and r["n"] == n]
            if not sel:
                continue
            cold, drv = med([r["cold_s"] for r in sel]), med([r["driver_s"] for r in sel])
            rep = med([r["replan_s"] for r in sel if "replan_s" in r])
            cc, dc = med([r["cold_cpu_s"] for r in sel]), med([r["driver_cpu_s"] for r in sel])
            rc = med([r["replan_cpu_s"] for r in sel if "replan_cpu_s" in r])
            print(
                f"| {method} | {n} | {len(sel)} | {sum(r['solved'] for r in sel)} | {ms(cold)} "
                f"| {ms(rep)} | {ms(drv)} | {cold / drv:.2f} | {rep / drv:.2f} | {ms(cc)} "
                f"| {ms(rc)} | {ms(dc)} | {cc / dc:.2f} |"
            )
    misses = [r["scene"] for r in rows if r.get("replan_hit") is False]
    same = all(r["plan_length"] == r["driver_length"] for r in rows if r["solved"])
    print(f"\nreplans answered from the cache: {not misses} {misses or ''}")
    print(f"our plans as long as the driver's (same optimal search): {same}")
    return rows


# --------------------------------------------------------------------------- process
def bench_process(args: argparse.Namespace) -> list[dict[str, Any]]:
    from utamp_gym.planning.fast_downward import downward_paths
    from utamp_gym.suites import suite_scenes

    _, driver = downward_paths()
    utamp = Path(sys.executable).with_name("utamp")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    five = [s.name for s in suite_scenes(args.suite) if s.n_objects == 5]
    names = five[:: max(1, len(five) // args.process_scenes)][: args.process_scenes]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            out = Path(tmp, name.replace("/", "-"))
            ours = [str(utamp), "plan", name, "--json"]
            subprocess.run([*ours, "--out", str(out)], env=env, check=True, capture_output=True)
            theirs = [sys.executable, str(driver), "--alias", "lama-first"]
            theirs += [str(out / "domain.pddl"), str(out / "problem.pddl")]
            for cmd in (ours, theirs):  # warm-up (byte-code caches, page cache)
                subprocess.run(cmd, env=env, cwd=out, check=True, capture_output=True)
            times: dict[str, list[tuple[float, float]]] = {"ours": [], "driver": []}
            for _ in range(args.process_runs):
                for key, cmd in (("ours", ours), ("driver", theirs)):
                    _, w, c = timed(
                        subprocess.run, cmd, env=env, cwd=out, check=True, capture_output=True
                    )
                    times[key].append((w, c))
            row = {"scene": name}
            for key, xs in times.items():
                row[f"{key}_s"] = med([w for w, _ in xs])
                row[f"{key}_cpu_s"] = med([c for _, c in xs])
            rows.append(row)
            print(f"{name}: utamp plan {ms(row['ours_s'])} ms, driver {ms(row['driver_s'])} ms")
    ours_w, drv_w = med([r["ours_s"] for r in rows]), med([r["driver_s"] for r in rows])
    ours_c, drv_c = med([r["ours_cpu_s"] for r in rows]), med([r["driver_cpu_s"] for r in rows])
    print(f"\n## Whole process, {len(rows)} five-object scenes x {args.process_runs} runs (ms)\n")
    print("| command | wall median | CPU median |")
    print("|---|---|---|")
    print(f"| `utamp plan SCENE --json` | {ms(ours_w)} | {ms(ours_c)} |")
    print(f"| `fast-downward.py --alias lama-first` | {ms(drv_w)} | {ms(drv_c)} |")
    print(f"| ratio | {ours_w / drv_w:.2f} | {ours_c / drv_c:.2f} |")
    return rows


# --------------------------------------------------------------------------- search
def bench_search(args: argparse.Namespace) -> list[dict[str, Any]]:
    from utamp_gym.planning.fast_downward import SEARCH_CONFIGS
    from utamp_gym.planning.methods import plan_scene
    from utamp_gym.planning.state_planner import StatePlanner
    from utamp_gym.suites import suite_scenes

    optimal = [s for s in SEARCH_CONFIGS if s.startswith("astar")]
    five = [s for s in suite_scenes(args.suite) if s.n_objects == 5]
    cases = [("utamp2-gt", s, {}) for s in five]
    cases += [("utamp1", s, {}) for s in five[:: args.utamp1_stride]]
    cases += [("utamp2-noisy", s, {"noise": 0.05, "seed": 1}) for s in five[::3]]
    rows = []
    for method, scene, kw in cases:
        for search in optimal:
            planner = StatePlanner(
                "utamp1" if method == "utamp1" else "utamp2", search=search, timeout=args.timeout
            )
            out = plan_scene(scene, method, planner=planner, timeout=args.timeout, **kw)
            plan_args = successor_args(out, steps=0)  # the initial state again: a cache hit
            walls, cpus = [], []
            for _ in range(args.repeats):
                res, w, c = timed(planner.plan, *plan_args)
                walls.append(w)
                cpus.append(c)
            rows.append(
                {
                    "method": method,
                    "scene": scene.name,
                    "search": search,
                    "solved": res.solved,
                    "length": len(res.plan),
                    "expanded": res.expanded,
                    "cold_s": out.planning_time_s,
                    "search_s": med(walls),
                    "search_cpu_s": med(cpus),
                }
            )
        print(
            f"{method} {scene.name}: "
            + ", ".join(f"{r['search']} {ms(r['search_s'])} ms" for r in rows[-len(optimal) :]),
            flush=True,
        )
    print("\n## Optimal search configurations (cached task: search only; medians, ms)\n")
    print("| method | tasks | unsolvable | search | wall | CPU | cold wall | expanded |")
    print("|---|---|---|---|---|---|---|---|")
    for method in ("utamp2-gt", "utamp1", "utamp2-noisy"):
        for search in optimal:
            sel = [r for r in rows if r["method"] == method and r["search"] == search]
            if not sel:
                continue
            print(
                f"| {method} | {len(sel)} | {sum(not r['solved'] for r in sel)} | {search} "
                f"| {ms(med([r['search_s'] for r in sel]))} "
                f"| {ms(med([r['search_cpu_s'] for r in sel]))} "
                f"| {ms(med([r['cold_s'] for r in sel]))} "
                f"| {med([r['expanded'] or 0 for r in sel]):.0f} |"
            )
    lengths: dict[tuple[str, str], set[int]] = {}
    for r in rows:
        lengths.setdefault((r["method"], r["scene"]), set()).add(r["length"])
    same = all(len(v) == 1 for v in lengths.values())
    print(f"\nall optimal searches give plans of equal length: {same}")
    return rows


# --------------------------------------------------------------------------- crosscheck
def bench_crosscheck(args: argparse.Namespace) -> list[dict[str, Any]]:
    from utamp_gym.planning.fast_downward import solve
    from utamp_gym.planning.methods import plan_scene
    from utamp_gym.suites import SUITES, suite_scenes

    rows = []
    for suite in SUITES:
        for k, scene in enumerate(suite_scenes(suite)):
            methods = ["utamp2-gt"]
            if suite == "pick-place" and k % args.utamp1_stride == 0:
                methods.append("utamp1")
            for method in methods:
                out = plan_scene(scene, method, search=args.search, timeout=args.timeout)
                fd = solve(
                    out.domain, out.problem, search=args.search, timeout=args.timeout,
                    translator="fd",
                )  # fmt: skip
                rows.append(
                    {
                        "scene": scene.name,
                        "method": method,
                        "ours": out.plan_length if out.solved else None,
                        "fd": len(fd.plan) if fd.solved else None,
                    }
                )
    bad = [r for r in rows if r["ours"] != r["fd"]]
    print(f"\n## Cross-check: our grounder + SAS vs Fast Downward's translator ({args.search})\n")
    print(f"{len(rows)} tasks, {len(rows) - len(bad)} with plans of equal length")
    for r in bad:
        print(f"- MISMATCH {r['scene']} {r['method']}: ours {r['ours']}, FD translator {r['fd']}")
    return rows


# --------------------------------------------------------------------------- policy
def bench_policy(args: argparse.Namespace) -> list[dict[str, Any]]:
    from utamp_gym.agents import PlannerPolicy
    from utamp_gym.env.kitchen import UTampKitchenEnv

    env = UTampKitchenEnv(grounding="symbolic", suite=args.suite, num_objects=5)
    policy = PlannerPolicy(env)
    rows = []
    for seed in range(args.episodes):
        obs, info = env.reset(seed=seed)
        policy.reset()
        before = len(policy.planning_times)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs, info))
            done = terminated or truncated
        times = policy.planning_times[before:]
        rows.append({"scene": env.scene.name, "calls": len(times), "planning_s": sum(times)})
    firsts, seen = [], set()
    for r in rows:
        r["first_of_scene"] = r["scene"] not in seen
        seen.add(r["scene"])
        firsts.append(r["first_of_scene"])
    per_ep = [r["planning_s"] for r in rows]
    print(f"\n## PlannerPolicy, five-object symbolic episodes ({args.episodes}, {args.suite})\n")
    print(
        f"planning time per episode: median {ms(med(per_ep))} ms, mean "
        f"{ms(statistics.fmean(per_ep))} ms; planner calls per episode: "
        f"{med([r['calls'] for r in rows]):.0f}; first episode of a scene "
        f"{ms(med([r['planning_s'] for r in rows if r['first_of_scene']]))} ms, later "
        f"{ms(med([r['planning_s'] for r in rows if not r['first_of_scene']]))} ms"
    )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sections", default="suite,process,search,crosscheck")
    ap.add_argument("--suite", default="pick-place")
    ap.add_argument("--stride", type=int, default=1, help="use every k-th scene (suite)")
    ap.add_argument("--utamp1-stride", type=int, default=6, help="UTAMP-1 on every k-th scene")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--process-scenes", type=int, default=5)
    ap.add_argument("--process-runs", type=int, default=5)
    ap.add_argument("--episodes", type=int, default=40, help="policy episodes")
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--search", default=None, help="default: the package's DEFAULT_SEARCH")
    ap.add_argument("--json", help="also write the raw rows here")
    args = ap.parse_args()
    sections = [s.strip() for s in args.sections.split(",") if s.strip()]
    unknown = sorted(set(sections) - set(SECTIONS))
    if unknown:
        ap.error(f"unknown section(s) {', '.join(unknown)}; valid: {', '.join(SECTIONS)}")
    if args.search is None and set(sections) - {"policy"}:
        from utamp_gym.planning.fast_downward import DEFAULT_SEARCH

        args.search = DEFAULT_SEARCH
    runners = {
        "suite": bench_suite,
        "process": bench_process,
        "search": bench_search,
        "crosscheck": bench_crosscheck,
        "policy": bench_policy,
    }
    out = {}
    for section in sections:
        out[section] = runners[section](args)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
