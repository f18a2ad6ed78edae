"""Round walls in an object's seen frame (`shape`): a circle fitted to a side wall's points
(`wall_fit`: its centre and top radius; also the pose tracker's round-body centre), and
whether a body's wall is round at all (`round_wall`), and a round body widened to an arc of
its own rim left outside the fitted circle (`widen_to_arc`)."""

from __future__ import annotations

import numpy as np

from utamp_gym.perception.grid import Grid, cells_of, components, dilate_disc, erode_disc

ROUND_RESIDUAL = 0.003  # m: a wall a circle does not fit this well is not round (a box's)
ARC_SPAN = 1.0  # of the radius: a piece beside a round body wider across than this is its rim
ARC_MIN_CELLS = 12  # cells: smaller leftovers are noise (`shape.MIN_MEMBER_CELLS`)


def wall_fit(
    wall: np.ndarray,
    centre: np.ndarray,
    radius: float,
    band: float = 0.01,
    rays: np.ndarray | None = None,
) -> tuple[np.ndarray, float] | None:
    """Centre and top radius of a round wall, which may flare: circles with one shared
    centre and a radius per height band of `band` m, fitted by linear least squares, the
    points farther than 4 mm from their band's circle dropped and the fit repeated (each
    band needs 12 points). The top radius is the median distance of the upper bands' points
    on the outer face (a flared wall's along a line in height, taken at the top): with the
    points' viewing `rays` (xy), those seen from outside (the ray points towards the axis;
    a wall's inner face, seen over the rim, looks outwards). Without rays, the third
    quartile of all of them (the inner face pulls the median in; the largest or the 90th
    percentile read a 7.0 cm mug as 7.4 cm, too wide for the hand with the rules'
    clearance, and the third quartile read tumblers 2 mm too wide)."""
    if len(wall) < 20:
        return None
    keep = np.ones(len(wall), dtype=bool)
    for _ in range(3):
        pts = wall[keep]
        bands = np.floor(pts[:, 2] / band).astype(int)
        ids, inverse, counts = np.unique(bands, return_inverse=True, return_counts=True)
        good = counts[inverse] >= 12
        if good.sum() < 20:
            return None
        pts, inverse = pts[good], inverse[good]
        used = np.unique(inverse)
        col = np.searchsorted(used, inverse)
        a = np.zeros((len(pts), 2 + len(used)))
        a[:, :2] = 2 * pts[:, :2]
        a[np.arange(len(pts)), 2 + col] = 1.0
        sol, *_ = np.linalg.lstsq(a, (pts[:, :2] ** 2).sum(axis=1), rcond=None)
        c = sol[:2]
        r2 = sol[2:] + c @ c
        if np.any(r2 <= 0) or np.linalg.norm(c - centre) > 0.5 * radius:
            return None
        radii = np.sqrt(r2)
        dist = np.linalg.norm(wall[:, :2] - c, axis=1)
        all_bands = np.floor(wall[:, 2] / band).astype(int)
        expected = np.interp(all_bands, ids[used], radii)
        new = np.abs(dist - expected) < 0.004
        if new.sum() < 20 or np.array_equal(new, keep):
            break
        keep = new
    # the outer surface: a wall's inner face (seen over a rim) is no part of the footprint
    dist = np.linalg.norm(wall[:, :2] - c, axis=1)
    bands = np.floor(wall[:, 2] / band).astype(int)
    top = bands.max()
    upper = (bands >= top - 1) & keep
    if upper.sum() < 5:
        upper = keep
    if rays is not None:
        outer = upper & (np.sum(rays[:, :2] * (wall[:, :2] - c), axis=1) < 0.0)
        if outer.sum() >= 10:
            z, d = wall[outer, 2], dist[outer]
            slope = 0.0  # a flared wall (a pan's) widens to its top: a line through the bands
            if float(np.ptp(z)) > 0.005:
                slope = max(float(np.polyfit(z, d, 1)[0]), 0.0)
            return c, float(np.median(d - slope * z) + slope * float(wall[:, 2].max()))
    return c, float(np.percentile(dist[upper], 75))


def round_wall(grid: Grid, local: np.ndarray, body: np.ndarray) -> bool:
    """Whether the side wall around `body` is round: a circle fitted to its points (mid
    height, near the outline) leaves them within `ROUND_RESIDUAL` of it (a rectangle's
    wall, or a body with a handle block fused to it, does not)."""
    outline = dilate_disc(body, 5.0) & ~erode_disc(body, 5.0)
    near = cells_of(grid, local, outline)
    zmax = float(np.percentile(local[:, 2], 98)) if len(local) else 0.0
    wall = local[near & (local[:, 2] > 0.2 * zmax) & (local[:, 2] < 0.8 * zmax)]
    blo, bhi = grid.bounds(body)
    fit = wall_fit(wall, (blo + bhi) / 2, float(np.mean(bhi - blo)) / 2)
    if fit is None:
        return True  # nothing to tell: keep the footprint's verdict
    centre, radius = fit
    dist = np.linalg.norm(wall[:, :2] - centre, axis=1)
    bands = np.floor(wall[:, 2] / 0.01).astype(int)
    resid = np.empty(len(dist))
    for b in np.unique(bands):  # per height band: a flared wall is round at every height
        sel = bands == b
        resid[sel] = np.abs(dist[sel] - np.median(dist[sel]))
    return float(np.median(resid)) <= max(ROUND_RESIDUAL, 0.03 * radius)


def widen_to_arc(
    grid: Grid, foot: np.ndarray, centre: np.ndarray, radius: float
) -> tuple[np.ndarray, float]:
    """The circle widened to an arc of the body's own rim left outside it. A plate's low,
    sloped rim gives the wall fit few points, and the circle can come out centimetres short
    (a 23 cm plate read 17 cm), leaving a crescent of the rim beside it that would be read
    as a handle. A handle is narrow across the direction it sticks out; a piece spanning
    more than `ARC_SPAN` radii across is the rim: its far edge and the circle's opposite edge
    bound the diameter, and its span across is a chord, at most the diameter."""
    disc = np.linalg.norm(grid.centres(np.ones(grid.shape, bool)) - centre, axis=1)
    rest = foot & ~dilate_disc((disc <= radius).reshape(grid.shape), 2.0)
    for piece in components(rest):
        if piece.sum() < ARC_MIN_CELLS:
            break
        cells = grid.centres(piece) - centre
        u = cells.mean(axis=0)
        if not np.linalg.norm(u):
            continue
        u = u / np.linalg.norm(u)
        v = np.array([-u[1], u[0]])
        across = cells @ v
        span = float(across.max() - across.min())
        if span <= ARC_SPAN * radius:
            continue
        far = float((cells @ u).max())
        new_r = max((far + radius) / 2, span / 2)
        return centre + u * (far - new_r), new_r
    return centre, radius


__all__ = ["ARC_SPAN", "ROUND_RESIDUAL", "round_wall", "wall_fit", "widen_to_arc"]
