"""An object's protruding members beyond its body, in its seen frame (`shape`): handles.

A handle belongs to the side it sticks out of. A bar held away from the body by thin posts
(a tray's handle bar) is trimmed to the bar, provided the table shows through the gap
between the posts from above (`table_seen_through`), and its thickness is measured from its
points between the posts, the middle `BAR_MIDDLE` of its length (the cells at the bar's
inner face also hold the posts' ends). An attached handle's box reaches the body; a box
body's face beside it is measured from the body's points beside the handle.
"""

from __future__ import annotations

import numpy as np

from utamp_gym.perception.grid import CELL, Grid, dilate_disc

BAR_MIDDLE = 0.6  # of a detached bar's length: its middle, clear of the posts at its ends


def side_of(vec: np.ndarray) -> str:
    if abs(vec[0]) >= abs(vec[1]):
        return "front" if vec[0] > 0 else "back"
    return "left" if vec[1] > 0 else "right"


def table_seen_through(
    grid: Grid, steep: np.ndarray, top: np.ndarray, counts: np.ndarray, z0: float
) -> np.ndarray:
    """Cells through which a view from above saw the table: the ray to a table point
    crosses the height of the object around it (its top within 1 cm) in a cell without
    points of the object. The table seen sideways under a handle does not count: that ray
    passed beside the handle at the handle's height."""
    out = np.zeros(grid.shape, dtype=bool)
    if not len(steep):
        return out
    from scipy import ndimage

    around = ndimage.maximum_filter(np.where(np.isfinite(top), top, 0.0), size=7)
    p, ray = steep[:, :3].copy(), steep[:, 3:]
    p[:, 2] -= z0
    i, j, inside = grid.index(p[:, :2])
    h = np.zeros(len(p))
    h[inside] = around[i[inside], j[inside]]
    xy = p[:, :2] + ((h - p[:, 2]) / ray[:, 2])[:, None] * ray[:, :2]
    i, j, inside = grid.index(xy)
    free = inside.copy()
    free[inside] = counts[i[inside], j[inside]] == 0
    out[i[free], j[free]] = True
    return out & ~dilate_disc(counts > 0, 1.0)


def bar_thickness(
    pts: np.ndarray, side: str, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A detached bar's extent along its outward axis from its points between the posts:
    the cells at the bar's inner face also hold the posts' ends (a tray's 2 cm bar read
    2.5 cm by all of its cells' points, too thick for the rules' fingers)."""
    ax = 0 if side in ("front", "back") else 1
    across = 1 - ax
    span = hi[across] - lo[across]
    mid = np.abs(pts[:, across] - (lo[across] + hi[across]) / 2) <= BAR_MIDDLE * span / 2
    if mid.sum() < 10:
        return lo, hi
    lo, hi = lo.copy(), hi.copy()
    lo[ax], hi[ax] = np.percentile(pts[mid, ax], [0.5, 99.5])
    return lo, hi


def face_beside(
    pts: np.ndarray, side: str, lat_lo: float, lat_hi: float, lo: np.ndarray, hi: np.ndarray
) -> None:
    """Moves a box body's face on `side` (in `lo` / `hi`) to where its points beside an
    attached handle spanning [`lat_lo`, `lat_hi`] across it put it: the cells along the
    handle's root hold the handle's points too (a 24 cm board read up to 24.5 cm)."""
    ax = 0 if side in ("front", "back") else 1
    lat = pts[:, 1 - ax]
    beside = (lat < lat_lo - 2 * CELL) | (lat > lat_hi + 2 * CELL)
    if beside.sum() < 20:
        return
    if side in ("back", "right"):
        lo[ax] = float(np.percentile(pts[beside, ax], 0.2))
    else:
        hi[ax] = float(np.percentile(pts[beside, ax], 99.8))


def _posts(line: np.ndarray, bar: int) -> bool:
    """Whether a slice across the handle (a 1-D mask) holds two runs or more whose ends lie
    at least half the bar's length (`bar` cells) apart."""
    v = np.asarray(line, dtype=np.int8)
    runs = np.count_nonzero(np.diff(np.concatenate([[0], v])) == 1)
    cells = np.nonzero(v)[0]
    return bool(runs >= 2 and cells[-1] - cells[0] + 1 >= 0.5 * bar)


def between(piece: np.ndarray, bar: np.ndarray) -> np.ndarray:
    """Cells of the piece's bounding box that the trimmed bar left out (the posts' gap)."""
    i, j = np.nonzero(piece)
    box = np.zeros_like(piece)
    box[i.min() : i.max() + 1, j.min() : j.max() + 1] = True
    return box & ~dilate_disc(bar, 1.0)


def trim_bar(piece: np.ndarray, side: str) -> tuple[np.ndarray, bool]:
    """A handle held away from the body by thin posts, trimmed to its bar (and True)."""
    axis = 0 if side in ("front", "back") else 1
    counts = piece.sum(axis=1 - axis)  # cells per slice along the outward axis
    peak = int(np.argmax(counts))
    lo = hi = peak
    while lo > 0 and counts[lo - 1] >= 0.5 * counts[peak]:
        lo -= 1
    while hi < len(counts) - 1 and counts[hi + 1] >= 0.5 * counts[peak]:
        hi += 1
    outward = side in ("front", "left")
    slices = np.nonzero(counts)[0]
    inner = slices[slices < lo] if outward else slices[slices > hi]  # between bar and body
    # posts: three slices or more, or a slice holding two runs as far apart as half the
    # bar (the posts at its ends, seen in a narrow gap); a ragged cell or two next to the
    # body is neither
    posts = any(_posts(np.take(piece, k, axis=axis), counts[peak]) for k in inner)
    if len(inner) < 3 and not posts:
        return piece, False
    keep = np.zeros(len(counts), dtype=bool)
    if outward:
        keep[lo:] = True
    else:
        keep[: hi + 1] = True
    out = piece.copy()
    if axis == 0:
        out[~keep, :] = False
    else:
        out[:, ~keep] = False
    return out, True


__all__ = [
    "bar_thickness",
    "between",
    "face_beside",
    "side_of",
    "table_seen_through",
    "trim_bar",
]
