"""What perception from rendered RGB-D costs, and how well it sees.

Three measurements, written to ``docs/results/perception_cost.{md,json}``:

* **per macro step, perception="rgbd"** — UTAMP-2-GT plans executed with the robot's poses
  from the cameras (`utamp_gym.perception.tracking`): the wall time spent rendering the looks and
  fitting the poses (``perception_s`` of every step's timings), median and p95, next to the
  step's physics (``sim_s``: stepping MuJoCo) and its whole wall time; target median 50 ms;
* **pose accuracy** — the camera estimate of every object against the simulator's pose
  after reset and after every step (position error in mm, heading error in degrees);
* **the survey** — `utamp2-perceived`'s first, careful look (six views at 640 x 480,
  colour, depth and instance masks) and the attribute fit, per episode.

The machine's load is printed with the times (they are wall-clock on a shared machine).

    python benchmarks/perception_cost.py [--scenes 8] [--suite pick-place] [--out docs/results]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

from utamp_gym.grounding import physics_backend
from utamp_gym.perception.objects import perceive_objects
from utamp_gym.planning.methods import plan_scene
from utamp_gym.provenance import commit, write_json, write_markdown
from utamp_gym.seeding import run_seed
from utamp_gym.sim.backend import MujocoBackend
from utamp_gym.sim.measure import obj_pose, pose_change
from utamp_gym.suites import suite_scenes

ROOT = Path(__file__).resolve().parents[1]
TARGET_MS = 50.0


def _pct(xs: list[float], q: float) -> float:
    return float(np.percentile(xs, q)) if xs else float("nan")


def _errors(backend: MujocoBackend) -> list[tuple[float, float]]:
    """(position mm, heading deg) errors of a fresh camera look at every object."""
    st = backend.state
    est = st.estimator
    est.new_look()
    out = []
    for name in st.world.body_ids:
        if st.held is not None and st.held.obj == name:
            continue
        d, a = pose_change(obj_pose(st, name), est.estimate(name, np.eye(4)))
        out.append((1000 * d, a))
    return out


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="pick-place")
    ap.add_argument("--scenes", type=int, default=8, help="every k-th scene, this many")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    pool = suite_scenes(args.suite)
    scenes = pool[:: max(1, len(pool) // args.scenes)][: args.scenes]
    load = os.getloadavg()
    step_perc, step_cpu, step_sim, step_wall, errors, survey, fit = [], [], [], [], [], [], []
    outcomes = []
    backend = physics_backend(perception="rgbd")
    start = time.perf_counter()
    try:
        for scene in scenes:
            rng = np.random.default_rng(run_seed(scene.name, 0))
            backend.reset(scene, rng)
            t = time.perf_counter()
            bundle = backend.survey()
            t_render = time.perf_counter() - t
            perceive_objects(bundle)
            survey.append(t_render)
            fit.append(time.perf_counter() - t - t_render)
            errors += _errors(backend)
            ok = True
            for action in plan_scene(scene, "utamp2-gt").plan:
                r = backend.execute(action)
                step_perc.append(r.timings.get("perception_s", 0.0))
                step_cpu.append(r.timings.get("perception_cpu_s", 0.0))
                step_sim.append(r.timings["sim_s"])
                step_wall.append(r.timings["wall_s"])
                if not r.success:
                    ok = False
                    break
                errors += _errors(backend)
            outcomes.append(ok)
            print(f"{scene.name}: {'ok' if ok else 'failed'}", flush=True)
    finally:
        backend.close()
    pos = [e[0] for e in errors]
    yaw = [e[1] for e in errors]
    ms = [1000 * x for x in step_perc]
    summary = {
        "suite": args.suite,
        "scenes": [s.name for s in scenes],
        "episodes_succeeded": sum(outcomes),
        "load_average_1_5_15": [round(v, 2) for v in load],
        "steps": len(ms),
        "perception_ms_median": round(statistics.median(ms), 1),
        "perception_ms_p95": round(_pct(ms, 95), 1),
        "perception_cpu_ms_median": round(1000 * statistics.median(step_cpu), 1),
        "perception_cpu_ms_p95": round(1000 * _pct(step_cpu, 95), 1),
        "physics_ms_median": round(1000 * statistics.median(step_sim), 1),
        "step_wall_ms_median": round(1000 * statistics.median(step_wall), 1),
        "pose_error_mm_median": round(statistics.median(pos), 2),
        "pose_error_mm_p95": round(_pct(pos, 95), 2),
        "heading_error_deg_median": round(statistics.median(yaw), 2),
        "heading_error_deg_p95": round(_pct(yaw, 95), 2),
        "pose_estimates": len(pos),
        "survey_render_ms_median": round(1000 * statistics.median(survey), 1),
        "survey_fit_ms_median": round(1000 * statistics.median(fit), 1),
        "wall_s": round(time.perf_counter() - start, 1),
    }
    verdict = "met" if summary["perception_ms_median"] <= TARGET_MS else "NOT met"
    lines = [
        f'Perception cost and accuracy, `perception="rgbd"` (`benchmarks/perception_cost.py`,'
        f" {len(scenes)} {args.suite} scenes, UTAMP-2-GT plans, seed 0; load average "
        f"{load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} on 2 cores while measuring).",
        "",
        "| per macro step | median | p95 |",
        "|---|---|---|",
        f"| perception (render + fit), wall ms | **{summary['perception_ms_median']}** | "
        f"{summary['perception_ms_p95']} |",
        f"| perception (render + fit), CPU ms of the process | "
        f"{summary['perception_cpu_ms_median']} | {summary['perception_cpu_ms_p95']} |",
        f"| physics (stepping MuJoCo), ms | {summary['physics_ms_median']} | "
        f"{round(1000 * _pct(step_sim, 95), 1)} |",
        f"| whole step (wall), ms | {summary['step_wall_ms_median']} | "
        f"{round(1000 * _pct(step_wall, 95), 1)} |",
        "",
        f"Target: perception median <= {TARGET_MS:.0f} ms per macro step: "
        f"{summary['perception_ms_median']} ms ({verdict}; {len(ms)} steps, "
        f"{summary['episodes_succeeded']}/{len(scenes)} episodes succeeded).",
        "",
        f"Pose error of the camera estimates ({len(pos)} estimates after reset and after every "
        f"step): position median {summary['pose_error_mm_median']} mm, p95 "
        f"{summary['pose_error_mm_p95']} mm; heading median "
        f"{summary['heading_error_deg_median']} deg, p95 {summary['heading_error_deg_p95']} deg.",
        "",
        f"`utamp2-perceived`'s survey per episode: rendering six 640 x 480 views (colour, depth,"
        f" instance masks) median {summary['survey_render_ms_median']} ms, fitting every "
        f"object's attributes median {summary['survey_fit_ms_median']} ms.",
    ]
    args.out.mkdir(parents=True, exist_ok=True)
    prov = write_json(args.out / "perception_cost.json", summary, indent=2)
    write_markdown(args.out / "perception_cost.md", "\n".join(lines) + "\n", prov)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
