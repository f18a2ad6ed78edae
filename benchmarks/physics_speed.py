"""Physics cost per episode: this code against an earlier commit, side by side in one run.

The earlier commit (``--base``, default f68ae5a) is checked out with ``git worktree add``
into a temporary folder. Two worker processes (this script with ``--worker``) run the same
venv, each with one tree first on ``PYTHONPATH``, and execute the same episodes
(`run_episode`: UTAMP-2-GT planned, then executed in MuJoCo at the default pose noise, as
``utamp run SCENE --seed S`` does). Episodes alternate between the two workers (ABBA...), so
the load of a shared machine hits both alike.

Per suite and object count it prints the median simulated seconds and `mj_step` calls per
episode, µs per `mj_step` (wall time inside `mj_step` over all calls), the median wall and
CPU time per episode (planning included; CPU counts the planner's subprocess) and the ratios
this / base; then where the simulated seconds go per macro phase (`physics_phases.PHASES`),
from a second pass of every episode with the phase profiler on. The second pass also checks
determinism: each version must give the same outcome row (success, reason, final stack, the
exact final poses) and the same `mj_step` count both times. Target: five-object episodes of
both suites at a median wall time <= 0.5x the base's.

Writes ``<out>.md`` (the speed table), ``<out>.json`` (every episode's figures) and
``physics_phases.md`` beside them (the phase table) for the docs (`docs/physics-speed.md`).

    python benchmarks/physics_speed.py [--base f68ae5a] [--suites pick-place,sliding]
        [--objects 2,3,4,5] [--stride 1] [--seeds 1] [--no-phases]
        [--out docs/results/physics_speed]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from compare import Worker, base_worktree, cpu_s, git, med, rounded  # benchmarks/ is on sys.path

os.environ.setdefault("MUJOCO_GL", "egl")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TARGET = 0.5  # five-object median wall time, this / base
DT = 0.002  # s, both versions' physics step


# --------------------------------------------------------------------------- worker
def _episode(scene: str, seed: int, phases: bool) -> dict[str, Any]:
    """Run one episode in this process (the tree on `PYTHONPATH`) and measure it."""
    sys.path.insert(0, str(HERE))
    from physics_phases import Meter

    try:  # this tree; the earlier commit's runner was `sim/execute.py`
        from utamp_gym.agents.runs import run_episode
    except ImportError:
        from utamp_gym.sim.execute import run_episode

    with Meter(phases=phases) as meter:
        cpu, t0 = cpu_s(), time.perf_counter()
        r = run_episode(scene, seed=seed)
        wall, cpu = time.perf_counter() - t0, cpu_s() - cpu
    failure = None if r.failure is None else str(r.failure.get("reason"))
    return {
        "scene": scene,
        "seed": seed,
        "success": r.success,
        "failure": failure,
        "outcome": [r.success, failure, r.final_stack, r.object_poses],
        "plan_steps": len(r.plan),
        "steps": meter.steps,
        "sim_s": meter.steps * DT,
        "step_wall_s": meter.step_wall_s,
        "contacts": meter.contacts / max(meter.steps, 1),
        "wall_s": wall,
        "cpu_s": cpu,
        "phases": dict(meter.by_phase),
    }


def worker() -> None:
    """Serve episodes: one JSON request per stdin line, one JSON answer per stdout line."""
    import utamp_gym

    out = sys.stdout
    sys.stdout = sys.stderr  # nothing else may write to the answer stream
    _episode("pick-place/000", 0, False)  # warm-up: imports, Pinocchio, OMPL, planner
    print(json.dumps({"ready": utamp_gym.__file__}), file=out, flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        print(json.dumps(_episode(req["scene"], req["seed"], req["phases"])), file=out, flush=True)


# --------------------------------------------------------------------------- driver
def summarise(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (suite, object count): medians and ratios of the timed pass."""
    out = []
    for suite, n in sorted({(r["suite"], r["n"]) for r in rows}):
        sel = [r for r in rows if r["suite"] == suite and r["n"] == n]
        row: dict[str, Any] = {"suite": suite, "objects": n, "episodes": len(sel) // 2}
        for v in ("base", "this"):
            mine = [r for r in sel if r["version"] == v]
            steps = sum(r["steps"] for r in mine)
            row[v] = {
                "success": sum(r["success"] for r in mine),
                "sim_s": med(r["sim_s"] for r in mine),
                "steps": med(r["steps"] for r in mine),
                "us_per_step": 1e6 * sum(r["step_wall_s"] for r in mine) / max(steps, 1),
                "contacts": sum(r["contacts"] * r["steps"] for r in mine) / max(steps, 1),
                "wall_s": med(r["wall_s"] for r in mine),
                "cpu_s": med(r["cpu_s"] for r in mine),
            }
        row["ratio"] = {k: row["this"][k] / row["base"][k] for k in row["this"] if k != "success"}
        pairs = {(r["scene"], r["seed"]): r for r in sel if r["version"] == "base"}
        per = [
            r["wall_s"] / pairs[(r["scene"], r["seed"])]["wall_s"]
            for r in sel
            if r["version"] == "this"
        ]
        row["ratio"]["wall_s_per_episode_median"] = med(per)
        out.append(row)
    return out


def _cell(s: dict[str, Any], key: str, fmt: str) -> str:
    """'base → this (ratio×)' of one summary figure."""
    b, t, q = s["base"][key], s["this"][key], s["ratio"][key]
    return f"{b:{fmt}} → {t:{fmt}} (**{q:.2f}×**)"


def speed_table(summary: list[dict[str, Any]], base: str, this: str, run: str) -> str:
    lines = [
        "| suite | objects | episodes | success base / this | simulated s | `mj_step` calls "
        "| contacts per step | µs per call | wall s per episode | CPU s per episode |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for s in summary:
        b, t = s["base"], s["this"]
        lines.append(
            f"| {s['suite']} | {s['objects']} | {s['episodes']} | {b['success']} / {t['success']} "
            f"| {_cell(s, 'sim_s', '.1f')} | {b['steps']:,.0f} → {t['steps']:,.0f} "
            f"| {b['contacts']:.0f} → {t['contacts']:.0f} "
            f"| {_cell(s, 'us_per_step', '.0f')} | {_cell(s, 'wall_s', '.2f')} "
            f"| {_cell(s, 'cpu_s', '.2f')} |"
        )
    lines.append("")
    lines.append(
        f"Medians per episode, base `{base}` → this `{this}` (ratio this / base); contacts per "
        f"step and µs per call (the wall time inside `mj_step`) are means over all steps. {run} "
        "Generated by `benchmarks/physics_speed.py`."
    )
    return "\n".join(lines) + "\n"


def phase_table(rows: list[dict[str, Any]], base: str, this: str) -> str:
    sys.path.insert(0, str(HERE))
    from physics_phases import PHASES

    suites = sorted({r["suite"] for r in rows})
    head = "| phase | " + " | ".join(f"{s}: base | {s}: this" for s in suites) + " |"
    lines = [head, "|---|" + "---|---|" * len(suites)]
    totals: dict[tuple[str, str], float] = {}
    means: dict[tuple[str, str, str], float] = {}
    for suite in suites:
        for v in ("base", "this"):
            mine = [r for r in rows if r["suite"] == suite and r["version"] == v]
            for p in PHASES:
                means[(suite, v, p)] = DT * sum(r["phases"].get(p, 0) for r in mine) / len(mine)
            totals[(suite, v)] = sum(r["sim_s"] for r in mine) / len(mine)
    for p in PHASES:
        if not any(means[(s, v, p)] for s in suites for v in ("base", "this")):
            continue
        cells = []
        for s in suites:
            for v in ("base", "this"):
                x = means[(s, v, p)]
                cells.append(f"{x:.2f} s ({100 * x / totals[(s, v)]:.0f} %)")
        lines.append(f"| {p} | " + " | ".join(cells) + " |")
    total = [f"**{totals[(s, v)]:.2f} s**" for s in suites for v in ("base", "this")]
    lines.append("| **all** | " + " | ".join(total) + " |")
    n = {s: len([r for r in rows if r["suite"] == s]) // 2 for s in suites}
    lines.append("")
    lines.append(
        "Simulated seconds per episode by macro phase (mean over "
        + ", ".join(f"{n[s]} {s}" for s in suites)
        + f" episodes), base `{base}` and this `{this}`. Generated by "
        "`benchmarks/physics_speed.py` (phase profiler: `benchmarks/physics_phases.py`)."
    )
    return "\n".join(lines) + "\n"


def episodes(suites: Sequence[str], objects: set[int], stride: int, seeds: int) -> list[dict]:
    from utamp_gym.suites import suite_scenes

    out = []
    for suite in suites:
        scenes = [s for s in suite_scenes(suite) if s.n_objects in objects][::stride]
        for scene in scenes:
            for seed in range(seeds):
                out.append(
                    {"suite": suite, "scene": scene.name, "n": scene.n_objects, "seed": seed}
                )
    return out


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--base", default="f68ae5a", help="earlier commit to compare with")
    ap.add_argument("--suites", default="pick-place,sliding")
    ap.add_argument("--objects", default="2,3,4,5", help="object counts to run")
    ap.add_argument("--stride", type=int, default=1, help="every k-th scene of each count")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--no-phases", action="store_true", help="skip the phase/determinism pass")
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "physics_speed"))
    return ap


def main() -> None:
    args = build_parser().parse_args()
    if args.worker:
        worker()
        return
    # imported here, not at the top: a worker runs this file on the base commit's tree
    from utamp_gym.provenance import commit, write_json, write_markdown

    this = commit()  # the provenance of what this run writes: the code as it is now
    base = git("rev-parse", "--short", args.base)
    jobs = episodes(
        args.suites.split(","), {int(n) for n in args.objects.split(",")}, args.stride, args.seeds
    )
    load0 = os.getloadavg()[0]
    print(f"{len(jobs)} episodes, base {base} vs this {this}; load {load0:.1f}", flush=True)
    started = time.perf_counter()
    rows: list[dict[str, Any]] = []
    phase_rows: list[dict[str, Any]] = []
    deterministic: list[str] = []
    with base_worktree(base, "physics_speed_") as tree:
        workers: dict[str, Worker] = {}
        try:
            workers = {
                v: Worker(v, t, Path(__file__), "--worker")
                for v, t in (("this", ROOT), ("base", tree))
            }
            for i, job in enumerate(jobs):
                order = ("this", "base") if i % 2 == 0 else ("base", "this")
                for v in order:
                    r = workers[v].ask(scene=job["scene"], seed=job["seed"], phases=False)
                    rows.append({**job, **r, "version": v})
                a, b = rows[-2:] if rows[-1]["version"] == "base" else rows[-1:-3:-1]
                print(
                    f"{job['scene']} seed {job['seed']}: this {'ok' if a['success'] else 'FAIL'}"
                    f" {a['sim_s']:.1f} sim s {a['wall_s']:.2f} s | base"
                    f" {'ok' if b['success'] else 'FAIL'} {b['sim_s']:.1f} sim s"
                    f" {b['wall_s']:.2f} s",
                    flush=True,
                )
            if not args.no_phases:
                for job in jobs:
                    for v in ("this", "base"):
                        r = workers[v].ask(scene=job["scene"], seed=job["seed"], phases=True)
                        phase_rows.append({**job, **r, "version": v})
                        timed = next(
                            x
                            for x in rows
                            if x["version"] == v
                            and (x["scene"], x["seed"]) == (job["scene"], job["seed"])
                        )
                        if r["outcome"] != timed["outcome"] or r["steps"] != timed["steps"]:
                            deterministic.append(f"{v} {job['scene']} seed {job['seed']}")
        finally:
            for w in workers.values():
                w.close()
    elapsed = time.perf_counter() - started

    summary = summarise(rows)
    run = (
        f"One run, {elapsed / 60:.0f} min, load average {load0:.1f} at the start and "
        f"{os.getloadavg()[0]:.1f} at the end ({os.cpu_count()} cores)."
    )
    table = speed_table(summary, base, this, run)
    print("\n" + table)
    differ = [
        f"{r['scene']} seed {r['seed']}"
        for r in rows
        if r["version"] == "this"
        and r["success"]
        != next(
            x["success"]
            for x in rows
            if x["version"] == "base" and (x["scene"], x["seed"]) == (r["scene"], r["seed"])
        )
    ]
    print(f"episodes whose success differs between the versions: {differ or 'none'}")
    for s in summary:
        if s["objects"] == 5:
            ok = s["ratio"]["wall_s"] <= TARGET
            print(
                f"{s['suite']}, five objects: median wall {s['ratio']['wall_s']:.2f}x the base's "
                f"(target <= {TARGET}): {'met' if ok else 'NOT met'}"
            )
    if phase_rows:
        phases = phase_table(phase_rows, base, this)
        print("\n" + phases)
        print(
            "determinism (same outcome row and mj_step count twice): "
            + ("held for every episode" if not deterministic else f"BROKEN: {deterministic}")
        )
    print(f"\n{elapsed:.0f} s in all; load {os.getloadavg()}")

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_markdown(out.with_suffix(".md"), table)
    report = {
        "base": base,
        "this": this,
        "load_average": os.getloadavg(),
        "elapsed_s": elapsed,
        "summary": summary,
        "differ": differ,
        "determinism_broken": deterministic,
        "episodes": [{k: v for k, v in r.items() if k != "outcome"} for r in rows],
        "phase_episodes": [{k: v for k, v in r.items() if k != "outcome"} for r in phase_rows],
    }
    write_json(out.with_suffix(".json"), rounded(report), indent=None)
    written = [out.with_suffix(".md"), out.with_suffix(".json")]
    if phase_rows:
        phases_md = out.parent / "physics_phases.md"
        write_markdown(phases_md, phases)
        written.append(phases_md)
    print("wrote " + ", ".join(str(p) for p in written))


if __name__ == "__main__":
    main()
