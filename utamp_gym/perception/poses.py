"""Object poses from a fused RGB-D look, for a robot that knows what it tracks.

Why a model: grasp and placement targets are decoded from an object's frame (origin at the
centre of its body's bottom face, x its front), so a pose must be given in that frame.
`PoseModel` is what the robot knows of the object's shape for that: its body (box or
cylinder) and the body's footprint in the object frame, the height range of the object and
the direction of its largest protrusion (a handle), and points on its surface. The robot's
own model — the catalogue type it decodes with, or the type it perceived — gives it
(`PoseModel.of`, `PoseModel.with_surface`); the pose itself comes from the cloud alone.
With surface points it is a model-based fit (`icp_pose`: iterative closest points in x, y,
z and heading); without, a fit of the shape's features (`feature_pose`):

* heading — a round body's from where its protrusion sticks out (a handle), else the
  previous belief's (it is symmetric); a box's from its footprint's smallest bounding
  rectangle, taken within 45 deg of the previous belief;
* body position — a round body's centre is a circle fitted to its side wall (`walls.wall_fit`),
  a box's the placement of its known footprint along each axis that holds the most points;
* height — the object's highest visible point less its known height above its origin;
  upright or inverted as believed (pick and place keep the orientation).

The estimate is level (objects rest on level surfaces; one in the hand is assumed level),
and ``None`` when the object shows too few points (occluded): the caller keeps its belief.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from utamp_gym.perception.cloud import voxel_keep
from utamp_gym.perception.grid import estimate_yaw, rotate
from utamp_gym.perception.walls import wall_fit
from utamp_gym.scene.catalogue import ObjectType

MIN_POINTS = 25
ICP_POINTS = 200  # observed points an ICP fit uses at most (evenly strided)
GOOD_FIT = 0.002  # m mean distance: a fit from the prior this good needs no second start
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
    surface: np.ndarray | None = None  # (M, 3) points on its surface (object frame)
    tree: Any = None  # a scipy cKDTree of `surface` (built once per object)
    normals: np.ndarray | None = None  # (M, 3) outward unit normals at `surface`

    @property
    def center(self) -> np.ndarray:
        """Centre of the object's bounding box (object frame)."""
        if self.surface is not None and len(self.surface):
            return (self.surface.min(axis=0) + self.surface.max(axis=0)) / 2
        return np.array([*self.body_center, sum(self.z_range) / 2])

    @property
    def round_(self) -> bool:
        """A round body with nothing sticking out: its heading cannot be seen."""
        return self.geom == "cylinder" and self.protrusion is None

    def with_surface(self, surface: np.ndarray, normals: np.ndarray | None = None) -> PoseModel:
        """This model with surface points (and their normals) for `icp_pose`."""
        from scipy.spatial import cKDTree

        pts = np.asarray(surface, dtype=float)
        nrm = None if normals is None else np.asarray(normals, dtype=float)
        return replace(self, surface=pts, tree=cKDTree(pts), normals=nrm)

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


def estimate_pose(
    points: np.ndarray,
    model: PoseModel,
    prior: np.ndarray,
    starts: Sequence[np.ndarray] = (),
) -> np.ndarray | None:
    """The object's pose (4x4) in its frame from its fused points: a model-based fit
    (`icp_pose`, also from `starts`: e.g. where the hand would have carried it) when the
    model has surface points, else the fit from the shape's features (`feature_pose`).
    `prior` is the current belief (orientation class, rough position)."""
    if len(points) < MIN_POINTS:
        return None
    if model.surface is not None and len(model.surface):
        return icp_pose(points, model, prior, starts=starts)
    return feature_pose(points, model, prior)


def icp_pose(
    points: np.ndarray,
    model: PoseModel,
    prior: np.ndarray,
    *,
    iterations: int = 20,
    reject: float = 0.01,
    starts: Sequence[np.ndarray] = (),
) -> np.ndarray | None:
    """Iterative closest points in four degrees of freedom (x, y, z, heading; the object is
    level, upright or inverted as `prior` is): each observed point is paired with the nearest
    point of the model's surface, pairs farther than the rejection distance dropped (it
    shrinks from 3x `reject`), and the rigid motion that best aligns the pairs (Procrustes
    about z, mean height) applied, until it settles. It starts from the prior, and from the
    prior moved onto the observed points (the model's top at the points' top, its centre over
    theirs: an object lifted or pushed since) and from any further `starts`; the start whose
    fit leaves the smallest mean distance wins."""
    if model.surface is None or len(points) < MIN_POINTS:
        return None
    points = _spread(points, ICP_POINTS)
    first = _icp(points, model, prior, iterations, reject)
    if first is not None and first[0] <= GOOD_FIT:
        return first[1]
    moved = prior.copy()
    corners = model.surface @ prior[:3, :3].T + prior[:3, 3]
    moved[:2, 3] += (
        np.median(points[:, :2], axis=0) - (corners[:, :2].min(0) + corners[:, :2].max(0)) / 2
    )
    moved[2, 3] += float(np.percentile(points[:, 2], 99.5) - corners[:, 2].max())
    best = first
    for start in (moved, *starts):
        fit = _icp(points, model, start, iterations, reject)
        if fit is not None and (best is None or fit[0] < best[0]):
            best = fit
    return None if best is None else best[1]


def _spread(points: np.ndarray, n: int) -> np.ndarray:
    """At most about `n` points spread evenly over the surface seen (one per voxel, the voxel
    grown until few enough are left), not where a close camera saw most of them."""
    if len(points) > 8 * n:  # a cheap thinning first: voxels of a huge cloud cost
        points = points[:: len(points) // (8 * n)]
    size = 0.004
    while len(points) > n:
        kept = points[voxel_keep(points, size)]
        if len(kept) <= n:
            return kept
        points, size = kept, size * 1.4
    return points


def _icp(
    points: np.ndarray, model: PoseModel, start: np.ndarray, iterations: int, reject: float
) -> tuple[float, np.ndarray] | None:
    """(mean paired distance, pose) of one ICP run from `start` (see `icp_pose`).

    With the model's surface normals each step is point-to-plane (the distances along the
    normals, linearised in x, y, z and the heading about the pairs' centre): points on a flat
    top then no longer pin a board's position, its edges do. Without normals it is
    point-to-point (Procrustes about z)."""
    from scipy.spatial import cKDTree

    assert model.surface is not None
    tree = model.tree if model.tree is not None else cKDTree(model.surface)
    flip = np.diag([1.0, -1.0, -1.0]) if start[2, 2] < 0 else np.eye(3)
    t = start[:3, 3].copy()
    yaw = _yaw_of(start[:3, :3])
    err = math.inf
    for k in range(iterations):
        rot = _rot(yaw) @ flip
        limit = reject * max(1.0, 3.0 - k / 2)
        dist, idx = tree.query((points - t) @ rot, distance_upper_bound=limit)
        keep = dist < limit  # observed points in the object frame, paired
        if keep.sum() < MIN_POINTS:
            return None
        err = float(dist[keep].mean())
        obs = points[keep]
        mod = model.surface[idx[keep]] @ rot.T + t  # their partners, in the world
        if model.normals is not None:
            normal = model.normals[idx[keep]] @ rot.T
            centre = mod.mean(axis=0)
            arm = mod - centre
            turn = normal[:, 1] * arm[:, 0] - normal[:, 0] * arm[:, 1]  # n . (z x arm)
            cols = [normal[:, 0], normal[:, 1], normal[:, 2]]
            if not model.round_:
                cols.append(turn)
            a = np.column_stack(cols)
            b = np.einsum("ij,ij->i", normal, obs - mod)
            x = np.linalg.solve(a.T @ a + 1e-6 * np.eye(a.shape[1]), a.T @ b)
            dtheta = float(x[3]) if not model.round_ else 0.0
            c, s_ = math.cos(dtheta), math.sin(dtheta)
            r2 = np.array([[c, -s_], [s_, c]])
            new_xy = r2 @ (t[:2] - centre[:2]) + centre[:2] + x[:2]
            t[2] += float(x[2])
        else:
            co, cm = obs[:, :2].mean(axis=0), mod[:, :2].mean(axis=0)
            pa, pb = obs[:, :2] - co, mod[:, :2] - cm
            dtheta = 0.0
            if not model.round_:  # a plain round body: its heading cannot be seen
                cross = float(np.sum(pb[:, 0] * pa[:, 1] - pb[:, 1] * pa[:, 0]))
                dtheta = math.atan2(cross, float(np.sum(pb * pa)))
            c, s_ = math.cos(dtheta), math.sin(dtheta)
            r2 = np.array([[c, -s_], [s_, c]])
            new_xy = r2 @ (t[:2] - cm) + co
            t[2] += float(np.mean(obs[:, 2] - mod[:, 2]))
        step = float(np.linalg.norm(new_xy - t[:2]))
        t[:2] = new_xy
        yaw += dtheta
        if k >= 2 and abs(dtheta) < 2e-4 and step < 2e-4:
            break
    out = np.eye(4)
    out[:3, :3] = _rot(yaw) @ flip
    out[:3, 3] = t
    return err, out


def _rot(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def feature_pose(points: np.ndarray, model: PoseModel, prior: np.ndarray) -> np.ndarray | None:
    """The pose from the shape's features (no model surface): module docstring."""
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
    rot = _rot(yaw) @ flip
    body_centre = rot @ np.array([*model.body_center, 0.0])
    out = np.eye(4)
    out[:3, :3] = rot
    out[:2, 3] = np.asarray(centre) - body_centre[:2]
    out[2, 3] = top + model.z_range[0] if inverted else top - model.z_range[1]
    return out


__all__ = ["PoseModel", "estimate_pose", "feature_pose", "icp_pose"]
