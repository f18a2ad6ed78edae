"""Point clouds from RGB-D views: back-projected, masked per object, fused across views.

Why numpy: back-projection is one matrix product per view (open3d's
`PointCloud.create_from_rgbd_image` gives the identical cloud; see docs/perception.md for the
measurement), and everything downstream works on plain arrays. A `Cloud` keeps, per point,
its world position, its colour (if the view had one), the view it came from and the
direction it was seen from (unit vector from the camera to the point).

`Scene3D` is the fused look at the whole table: every object's cloud plus the points of
everything else (background: table and floor; the robot), which the attribute and pose
fitting need to find what an object stands on and what covers it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from utamp_gym.contract.views import BACKGROUND, ViewBundle

MAX_RANGE = 4.0  # m: depth beyond this is no return (the renderer's far plane)
NEAR_PIXELS = 24  # background pixels this close to an object's image box are kept
VOXEL = 0.002  # m: fused clouds keep one point per voxel of this size


@dataclass(frozen=True, eq=False)
class Cloud:
    """Points (N, 3), colours (N, 3) uint8 or None, view index (N,), viewing rays (N, 3)."""

    points: np.ndarray
    colours: np.ndarray | None
    view: np.ndarray
    rays: np.ndarray

    def __len__(self) -> int:
        return len(self.points)

    def subset(self, keep: np.ndarray) -> Cloud:
        colours = None if self.colours is None else self.colours[keep]
        return Cloud(self.points[keep], colours, self.view[keep], self.rays[keep])


@dataclass(frozen=True, eq=False)
class Scene3D:
    """A fused look: per-instance clouds and the points of everything else."""

    objects: dict[int, Cloud]
    background: np.ndarray  # (M, 3) table and floor points
    robot: np.ndarray  # (K, 3) points on the robot
    background_steep: np.ndarray  # (S, 6): background points seen from above (rays down 30+
    # deg) and their viewing rays

    def others(self, instance: int) -> np.ndarray:
        """Points of every other object (not the background, not the robot)."""
        parts = [c.points for i, c in self.objects.items() if i != instance]
        return np.concatenate(parts) if parts else np.zeros((0, 3))


def _near_objects(instances: np.ndarray) -> np.ndarray:
    """Pixels of objects, and of anything else within `NEAR_PIXELS` of an object's image box
    (the table around and under objects; far background is not needed)."""
    out = instances > 0
    if not out.any():
        return out
    h, w = instances.shape
    ids = instances[out]
    vs, us = np.nonzero(out)
    for i in np.unique(ids):
        sel = ids == i
        v0, v1 = max(vs[sel].min() - NEAR_PIXELS, 0), min(vs[sel].max() + NEAR_PIXELS + 1, h)
        u0, u1 = max(us[sel].min() - NEAR_PIXELS, 0), min(us[sel].max() + NEAR_PIXELS + 1, w)
        out[v0:v1, u0:u1] = True
    return out


def fuse(
    bundle: ViewBundle, *, stride: int = 1, voxel: float = VOXEL, objects_only: bool = False
) -> Scene3D:
    """Back-project every view and fuse the points per instance (every `stride`-th pixel),
    keeping one point per `voxel` (objects; 1.5 voxels for the background; 0: all points).
    `objects_only` skips the background and the robot (pose fitting needs neither)."""
    if objects_only:
        return _objects_only(bundle, stride)
    per: dict[int, list[tuple[np.ndarray, np.ndarray | None, np.ndarray, np.ndarray]]] = {}
    background, robot, steep = [], [], []
    for k, view in enumerate(bundle.views):
        valid = (view.depth > 0) & (view.depth < MAX_RANGE) & _near_objects(view.instances)
        if stride > 1:
            sub = np.zeros_like(valid)
            sub[::stride, ::stride] = True
            valid &= sub
        points = view.points(valid)
        ids = view.instances[valid]
        colours = None if view.rgb is None else view.rgb[valid]
        rays = points - view.position
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        background.append(points[ids == BACKGROUND])
        down = (ids == BACKGROUND) & (rays[:, 2] < -0.5)
        steep.append(np.column_stack([points[down], rays[down]]))
        robot.append(points[ids < 0])
        for i in np.unique(ids[ids > 0]):
            sel = ids == i
            per.setdefault(int(i), []).append(
                (
                    points[sel],
                    None if colours is None else colours[sel],
                    np.full(int(sel.sum()), k, dtype=np.int32),
                    rays[sel],
                )
            )
    objects = {}
    for i, chunks in per.items():
        has_rgb = all(c[1] is not None for c in chunks)
        cloud = Cloud(
            np.concatenate([c[0] for c in chunks]),
            np.concatenate([c[1] for c in chunks]) if has_rgb else None,  # type: ignore[misc]
            np.concatenate([c[2] for c in chunks]),
            np.concatenate([c[3] for c in chunks]),
        )
        objects[i] = cloud.subset(voxel_keep(cloud.points, voxel))
    empty = np.zeros((0, 3))
    bg = np.concatenate(background) if background else empty
    rb = np.concatenate(robot) if robot else empty
    st = np.concatenate(steep) if steep else np.zeros((0, 6))
    return Scene3D(
        objects,
        bg[voxel_keep(bg, 1.5 * voxel)],
        rb[voxel_keep(rb, 2 * voxel)],
        st[voxel_keep(st[:, :3], 1.5 * voxel)],
    )


def _objects_only(bundle: ViewBundle, stride: int) -> Scene3D:
    """The objects' points of every view, fused per instance (no colours, no rays)."""
    per: dict[int, list[np.ndarray]] = {}
    for view in bundle.views:
        valid = (view.instances > 0) & (view.depth > 0) & (view.depth < MAX_RANGE)
        if stride > 1:
            valid[1::stride] = False
            valid[:, 1::stride] = False
        points = view.points(valid)
        ids = view.instances[valid]
        order = np.argsort(ids, kind="stable")
        ids, points = ids[order], points[order]
        cuts = np.flatnonzero(np.diff(ids)) + 1
        for chunk_ids, chunk in zip(np.split(ids, cuts), np.split(points, cuts), strict=True):
            if len(chunk_ids):
                per.setdefault(int(chunk_ids[0]), []).append(chunk)
    empty = np.zeros((0, 3))
    objects = {}
    for i, chunks in per.items():
        pts = np.concatenate(chunks)
        objects[i] = Cloud(pts, None, np.zeros(len(pts), dtype=np.int32), np.zeros_like(pts))
    return Scene3D(objects, empty, empty, np.zeros((0, 6)))


def voxel_keep(points: np.ndarray, size: float) -> np.ndarray:
    """Indices keeping the first point of every occupied voxel of `size` m (sorted)."""
    if len(points) == 0 or size <= 0:
        return np.arange(len(points))
    keys = np.floor(points / size).astype(np.int64)
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    flat = (keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]
    _, first = np.unique(flat, return_index=True)
    return np.sort(first)


__all__ = ["Cloud", "Scene3D", "fuse"]
