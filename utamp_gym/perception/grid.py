"""Top-view grids of a point cloud in an object's own frame, and the morphology on them.

An object's points are turned into its *seen frame* (z up, x along its estimated yaw) and
binned into square cells (`CELL` m): per cell the number of points and the highest one.
The footprint, the body (an opening of the footprint), protruding members and the shape
of the top surface are all read from such grids. Morphology with large structuring
elements goes through distance transforms (an erosion by a disc of radius r is the set
farther than r from the outside), which costs the same for any radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

CELL = 0.003  # m


@dataclass(frozen=True, eq=False)
class Grid:
    """A regular grid over the xy rectangle starting at `lo` (cell (0, 0)) of `shape` cells."""

    lo: np.ndarray
    shape: tuple[int, int]
    cell: float = CELL

    @classmethod
    def around(cls, xy: np.ndarray, margin: float, cell: float = CELL) -> Grid:
        lo = xy.min(axis=0) - margin
        hi = xy.max(axis=0) + margin
        shape = tuple(int(v) for v in np.ceil((hi - lo) / cell).astype(int) + 1)
        return cls(lo, shape, cell)  # type: ignore[arg-type]

    def index(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cell indices (i, j) of points and whether they fall inside the grid."""
        ij = np.floor((xy - self.lo) / self.cell).astype(int)
        inside = (ij[:, 0] >= 0) & (ij[:, 1] >= 0)
        inside &= (ij[:, 0] < self.shape[0]) & (ij[:, 1] < self.shape[1])
        return ij[:, 0], ij[:, 1], inside

    def centres(self, mask: np.ndarray) -> np.ndarray:
        """xy centres (N, 2) of the cells in `mask`."""
        i, j = np.nonzero(mask)
        return self.lo + (np.stack([i, j], axis=1) + 0.5) * self.cell

    def counts(self, points: np.ndarray) -> np.ndarray:
        i, j, inside = self.index(points[:, :2])
        out = np.zeros(self.shape, dtype=np.int32)
        np.add.at(out, (i[inside], j[inside]), 1)
        return out

    def top(self, points: np.ndarray) -> np.ndarray:
        """Highest z per cell (-inf where no point falls)."""
        i, j, inside = self.index(points[:, :2])
        out = np.full(self.shape, -np.inf)
        np.maximum.at(out, (i[inside], j[inside]), points[inside, 2])
        return out

    def bottom(self, points: np.ndarray) -> np.ndarray:
        """Lowest z per cell (+inf where no point falls)."""
        i, j, inside = self.index(points[:, :2])
        out = np.full(self.shape, np.inf)
        np.minimum.at(out, (i[inside], j[inside]), points[inside, 2])
        return out

    def bounds(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """xy min and max corners of the cells in `mask`."""
        i, j = np.nonzero(mask)
        lo = self.lo + np.array([i.min(), j.min()]) * self.cell
        hi = self.lo + (np.array([i.max(), j.max()]) + 1) * self.cell
        return lo, hi


def erode_disc(mask: np.ndarray, radius: float) -> np.ndarray:
    """Cells farther than `radius` (cells) from the outside of `mask`."""
    return ndimage.distance_transform_edt(mask) > radius


def dilate_disc(mask: np.ndarray, radius: float) -> np.ndarray:
    """Cells within `radius` (cells) of `mask`."""
    if not mask.any():
        return mask.copy()
    return ndimage.distance_transform_edt(~mask) <= radius


def open_disc(mask: np.ndarray, radius: float) -> np.ndarray:
    """Morphological opening by a disc (what discs of `radius` cells can sweep inside)."""
    return dilate_disc(erode_disc(mask, radius), radius) & mask


def open_square(mask: np.ndarray, half: int) -> np.ndarray:
    """Morphological opening by an axis-aligned square of half-side `half` cells."""
    if half < 1:
        return mask.copy()
    size = 2 * half + 1  # separable min / max filters: fast for any size
    eroded = ndimage.minimum_filter(mask.astype(np.uint8), size=size, mode="constant")
    return ndimage.maximum_filter(eroded, size=size, mode="constant").astype(bool) & mask


def footprint(counts: np.ndarray, extra: np.ndarray | None = None) -> np.ndarray:
    """Cells with points (or in `extra`), small gaps closed and enclosed holes filled."""
    occ = counts > 0 if extra is None else (counts > 0) | extra
    closed = ndimage.binary_closing(occ, structure=np.ones((3, 3), bool), border_value=0) | occ
    return ndimage.binary_fill_holes(closed)


def components(mask: np.ndarray) -> list[np.ndarray]:
    """The 8-connected components of `mask`, largest first."""
    labels, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
    parts = [labels == k for k in range(1, n + 1)]
    return sorted(parts, key=lambda m: -int(m.sum()))


def rotate(xy: np.ndarray, angle: float) -> np.ndarray:
    """Rotate 2-D points (N, 2) counter-clockwise by `angle` (rad) about the origin."""
    c, s = math.cos(angle), math.sin(angle)
    return xy @ np.array([[c, s], [-s, c]])


def estimate_yaw(xy: np.ndarray, prior: float = 0.0) -> float:
    """Heading of a footprint in [prior - 45, prior + 45) deg: the rotation that minimises
    its axis-aligned bounding rectangle (over the convex hull's edge directions); a round
    footprint, where no direction is clearly better, keeps `prior`."""
    from scipy.spatial import ConvexHull, QhullError

    if len(xy) < 5:
        return prior
    try:
        hull = xy[ConvexHull(xy).vertices]
        if len(hull) > 64:  # every direction's box is set by a few extreme points
            hull = xy[ConvexHull(np.round(xy, 3)).vertices]
    except QhullError:
        return prior
    edges = np.roll(hull, -1, axis=0) - hull
    angles = np.arctan2(edges[:, 1], edges[:, 0])
    candidates = np.concatenate([[prior], angles])
    best, best_area, prior_area = prior, math.inf, math.inf
    for a in candidates:
        a = prior + (((a - prior) + math.pi / 4) % (math.pi / 2)) - math.pi / 4
        local = rotate(hull, -a)
        area = float(np.prod(local.max(axis=0) - local.min(axis=0)))
        if a == prior:
            prior_area = area
        if area < best_area - 1e-12:
            best, best_area = a, area
    # round footprints: every direction is within a few per cent; keep the prior then
    return prior if prior_area <= best_area * 1.02 else float(best)


def cells_of(grid: Grid, pts: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Which points fall into the cells of `mask`."""
    i, j, inside = grid.index(pts[:, :2])
    out = np.zeros(len(pts), dtype=bool)
    out[inside] = mask[i[inside], j[inside]]
    return out


__all__ = [
    "CELL",
    "Grid",
    "cells_of",
    "components",
    "dilate_disc",
    "erode_disc",
    "estimate_yaw",
    "footprint",
    "open_disc",
    "open_square",
    "rotate",
]
