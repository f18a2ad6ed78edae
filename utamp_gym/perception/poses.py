"""Object poses from a fused RGB-D look, for a robot that knows roughly what it tracks.

Why a model: grasp and placement targets are decoded from an object's frame (origin at the
centre of its body's bottom face, x its front), so a pose must be given in that frame.
`PoseModel` is what the robot knows of the object's shape for that: its body (box or
cylinder) and the body's footprint in the object frame, the height range of the object and
the direction of its largest protrusion (a handle). The robot's own model — the catalogue
type it decodes with, or the type it perceived — gives it (`PoseModel.of`); the pose itself
comes from the cloud alone (`estimate_pose`):

* heading — a round body's from where its protrusion sticks out (a handle), else the
  previous belief's (it is symmetric); a box's from its footprint's smallest bounding
  rectangle, taken within 45 deg of the previous belief;
* body position — a round body's centre is a circle fitted to its side wall (`shape.wall_fit`),
  a box's the placement of its known footprint along each axis that holds the most points;
* height — the object's highest visible point less its known height above its origin;
  upright or inverted as believed (pick and place keep the orientation).

The estimate is level (objects rest on level surfaces; one in the hand is assumed level),
and ``None`` when the object shows too few points (occluded): the caller keeps its belief.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from utamp_gym.perception.grid import estimate_yaw, rotate
from utamp_gym.perception.shape import wall_fit
from utamp_gym.scene.catalogue import ObjectType

MIN_POINTS = 25
PROTRUSION = 0.006  # m beyond the body's radius: a point of a handle
STEP = 0.001  # m, placement search step of a box's footprint


@dataclass(frozen=True)
class PoseModel:
    """What pose tracking needs of an object's shape (module docstring)."""

    geom: str  # body: box | cylinder
    body_center: tuple[float, float]  # object frame
    body_half: tuple[float, float]  # half-extents of the body's footprint
    z_range: tuple[float, float]  # lowest and highest point of the object (object frame)
    protrusion: float | None  # angle of the largest protrusion from the body centre
    symmetric: bool = False  # two protrusions half a turn apart (a tray, a pot)

    @classmethod
    def of(cls, t: ObjectType) -> PoseModel:
        body = t.body.box
        centre = ((body.min[0] + body.max[0]) / 2, (body.min[1] + body.max[1]) / 2)
        half = ((body.max[0] - body.min[0]) / 2, (body.max[1] - body.min[1]) / 2)
        sticking = [
            m
            for m in t.members.values()
            if m.kind == "handle" and not body.contains_xy(m.box, tol=1e-6)
        ]
        angle, symmetric = None, False
        if sticking:
            big = max(sticking, key=lambda m: float(np.prod(m.box.size[:2])))
            c = big.box.center
            angle = math.atan2(c[1] - centre[1], c[0] - centre[0])
            symmetric = any(
                abs(
                    abs(
                        math.atan2(m.box.center[1] - centre[1], m.box.center[0] - centre[0]) - angle
                    )
                    - math.pi
                )
                < 0.2
                for m in sticking
            )
        return cls(
            t.body.geom,
            centre,
            half,
            (float(t.bbox.min[2]), float(t.bbox.max[2])),
            angle,
            symmetric,
        )


def _snap(angle: float, prior: float, period: float) -> float:
    """`angle` plus a multiple of `period`, nearest to `prior`."""
    return prior + ((angle - prior + period / 2) % period) - period / 2


def _yaw_of(rot: np.ndarray) -> float:
    return math.atan2(rot[1, 0], rot[0, 0])


def estimate_pose(points: np.ndarray, model: PoseModel, prior: np.ndarray) -> np.ndarray | None:
    """The object's pose (4x4) in its frame from its fused points (module docstring);
    `prior` is the current belief (its orientation class and heading are kept or refined)."""
    if len(points) < MIN_POINTS:
        return None
    inverted = prior[2, 2] < 0
    prior_yaw = _yaw_of(prior[:3, :3])
    top = float(np.percentile(points[:, 2], 99.5))
    height = model.z_range[1] - model.z_range[0]
    xy = points[:, :2]
    if model.geom == "cylinder":
        r0 = float(np.mean(model.body_half))
        guess = np.median(xy, axis=0)
        wall = points[points[:, 2] < top - 0.1 * height]
        fit = wall_fit(wall, guess, r0) if len(wall) >= 20 else None
        if fit is None:
            return None
        centre, radius = fit
        yaw = prior_yaw
        if model.protrusion is not None:
            d = np.linalg.norm(xy - centre, axis=1)
            out = xy[d > max(radius, r0) + PROTRUSION]
            if len(out) >= 5:
                seen = math.atan2(*(out.mean(axis=0) - centre)[::-1])
                # the model's angle is in the object frame; inverted, y is mirrored
                own = -model.protrusion if inverted else model.protrusion
                period = math.pi if model.symmetric else 2 * math.pi
                yaw = _snap(seen - own, prior_yaw, period)
    else:
        yaw = estimate_yaw(xy, prior_yaw)
        local = rotate(xy, -yaw)
        half = np.asarray(model.body_half)
        centre_local = np.zeros(2)
        for ax in (0, 1):
            lo, hi = float(local[:, ax].min()), float(local[:, ax].max())
            span = 2 * half[ax]
            if hi - lo <= span + STEP:
                centre_local[ax] = (lo + hi) / 2
                continue
            starts = np.arange(lo, hi - span + STEP, STEP)
            coord = np.sort(local[:, ax])
            counts = np.searchsorted(coord, starts + span) - np.searchsorted(coord, starts)
            best = np.flatnonzero(counts >= counts.max() - max(2, 0.01 * len(coord)))
            centre_local[ax] = float(starts[best].mean()) + half[ax]
        centre = rotate(centre_local[None, :], yaw)[0]
    flip = np.diag([1.0, -1.0, -1.0]) if inverted else np.eye(3)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ flip
    body_centre = rot @ np.array([*model.body_center, 0.0])
    out = np.eye(4)
    out[:3, :3] = rot
    out[:2, 3] = np.asarray(centre) - body_centre[:2]
    out[2, 3] = top + model.z_range[0] if inverted else top - model.z_range[1]
    return out


__all__ = ["PoseModel", "estimate_pose"]
