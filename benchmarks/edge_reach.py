"""Which table edges the Panda reaches for an edge pinch (issue #39, slide-to-edge).

    nice -n 5 python benchmarks/edge_reach.py [--step 0.05] [--out docs/results/edge_reach]

A board slid until it overhangs a table edge is pinched there from the side: the TCP just
outside the edge (`OUTSIDE`) at the board's mid-height (`HEIGHTS` above the table top),
approaching horizontally into the table (or pitched `PITCHES` down), fingers closing
vertically across the board. For every edge of the procedural table (the scene's
``kitchen-table``, robot base at the origin) this samples points along the edge every
``--step`` m and asks the arm's IK (`utamp_gym.robot.kinematics.PandaKinematics`, joint
limits, no collision check) for a configuration at any of those poses. Writes
``<out>.json`` and ``<out>.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from grasp_coverage import lone_scene
from result_page import write_page

from utamp_gym.provenance import commit
from utamp_gym.robot.kinematics import HOME_Q, PandaKinematics

OUTSIDE = 0.03  # m beyond the edge: the overhang the pads close on
HEIGHTS = (0.005, 0.02)  # m above the table top (a board's mid-height)
PITCHES = (0.0, 0.5)  # rad the approach points down from horizontal
BASE_CLEARANCE = 0.2  # m: points closer to the base's axis are inside the robot's base


def edge_points(step: float) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    """Per edge: (point on the edge, direction into the table) every `step` m."""
    box = lone_scene("chopping-board", 0).table.body.box
    (x0, y0, _), (x1, y1, _) = box.min, box.max
    xs = np.arange(x0, x1 + 1e-9, step)
    ys = np.arange(y0, y1 + 1e-9, step)
    return {
        f"near (x = {x0:+.2f})": [(np.array([x0, y]), np.array([1.0, 0.0])) for y in ys],
        f"far (x = {x1:+.2f})": [(np.array([x1, y]), np.array([-1.0, 0.0])) for y in ys],
        f"left (y = {y1:+.2f})": [(np.array([x, y1]), np.array([0.0, -1.0])) for x in xs],
        f"right (y = {y0:+.2f})": [(np.array([x, y0]), np.array([0.0, 1.0])) for x in xs],
    }


def pinch_pose(point: np.ndarray, inward: np.ndarray, height: float, pitch: float) -> np.ndarray:
    """TCP pose `OUTSIDE` beyond `point`, approaching along `inward` pitched down by
    `pitch`, the fingers closing in the vertical plane through the approach."""
    d = np.array([inward[0], inward[1], 0.0])
    z = np.cos(pitch) * d + np.array([0.0, 0.0, -np.sin(pitch)])
    x = np.cross(np.array([0.0, 0.0, 1.0]), d)  # horizontal, across the approach
    y = np.cross(z, x)
    out = np.eye(4)
    out[:3, :3] = np.column_stack([x, y, z])
    out[:3, 3] = [*(point - OUTSIDE * inward), height]
    return out


def reachable(kin: PandaKinematics, point: np.ndarray, inward: np.ndarray) -> bool:
    rng = np.random.default_rng(0)
    seed = np.array(HOME_Q)
    seed[0] = np.arctan2(point[1], point[0])
    for height in HEIGHTS:
        for pitch in PITCHES:
            res = kin.ik(pinch_pose(point, inward, height, pitch), seed, rng, max_attempts=12)
            if res.success:
                return True
    return False


def measure(step: float) -> dict[str, Any]:
    kin = PandaKinematics()
    out: dict[str, Any] = {}
    for edge, points in edge_points(step).items():
        rows = []
        for point, inward in points:
            dist = float(np.hypot(*point))
            ok = dist >= BASE_CLEARANCE and reachable(kin, point, inward)
            rows.append({"x": round(float(point[0]), 3), "y": round(float(point[1]), 3),
                         "base_distance": round(dist, 3), "reached": ok})  # fmt: skip
        out[edge] = rows
    return out


def markdown(data: dict[str, Any]) -> str:
    heights = ", ".join(f"{h * 100:.1f}" for h in HEIGHTS)
    lines = [
        "<!-- written by benchmarks/edge_reach.py; do not edit -->",
        "",
        "Where the Panda reaches an edge pinch (TCP "
        f"{OUTSIDE * 100:.0f} cm beyond the table edge, {heights} cm "
        "above the top, approaching into the table horizontally or pitched down "
        f"{', '.join(f'{p:.1f}' for p in PITCHES)} rad; IK within the joint limits, no "
        f"collision check; points within {BASE_CLEARANCE} m of the base's axis skipped), "
        f"every {data['step']} m along each edge of the procedural table.",
        "",
        "| edge | points | reached | where |",
        "|---|---|---|---|",
    ]
    for edge, rows in data["edges"].items():
        hit = [r for r in rows if r["reached"]]
        key = "y" if edge.startswith(("near", "far")) else "x"
        where = (
            f"{key} from {min(r[key] for r in hit):+.2f} to {max(r[key] for r in hit):+.2f}"
            if hit
            else "nowhere"
        )
        lines.append(f"| {edge} | {len(rows)} | {len(hit)} | {where} |")
    lines.append("")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.05)
    ap.add_argument("--out", default="docs/results/edge_reach")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()
    start = time.perf_counter()
    data = {"step": args.step, "edges": measure(args.step)}
    write_page(args.out, data, markdown, start)


if __name__ == "__main__":
    main()
