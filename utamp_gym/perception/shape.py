"""An object's geometry from its fused cloud: body, protruding members, its top surface.

Everything is measured in the object's *seen frame*: origin at the centre of the body's
footprint on the surface the object stands on, z up, x along the estimated heading
(`grid.estimate_yaw`; objects stand axis-aligned with the table, so the heading is taken
within 45 deg of the world's x axis). The steps (`fit_shape`):

1. **support** — the height of the surface around the footprint (table, a tray's floor, a
   board's top) that is no higher than the object's lowest point: the object stands on it;
2. **footprint** — the cells of a top-view grid (`grid.CELL`) holding the object's points,
   small gaps closed and holes (what covers the object, seen from above) filled;
3. **body** — the footprint opened with a disc of 0.6 times its largest inscribed radius:
   thinner protrusions (handles) vanish, the body stays. If the opened region fills its
   bounding rectangle (more than `BOX_FILL`) the body is a box, opened again with a square
   so that its corners survive; else a cylinder, whose centre and radius are a least-squares
   circle fitted to the points of its side wall;
4. **members** — what is left of the footprint beyond the body: each connected piece of
   at least `MIN_MEMBER_CELLS` is a handle on the side it sticks out of; a bar held away from
   the body by thin posts (a tray's handle) is trimmed to the bar, and its thickness is
   measured between the posts (its middle `BAR_MIDDLE`); an attached handle's box reaches
   the body. A narrow part standing on top of the body (a bottle's neck) is found
   from the heights: a plateau of less than half the body's area at least `NECK_RISE` above
   the rest;
5. **top** — the shape of the body's top from its visible heights (cells covered by other
   objects are left out): *flat* (nearly all of it at one height), *round* (lower towards
   its outline all around: a dome), or lower inside than at a rim running round it: a
   *flat* well inside a rim when shallow (depth below `WELL_RATIO` of the opening),
   *concave* (a dish whose walls flare from a smaller floor, or whose outer wall flares by
   more than `DISH_FLARE`: a pan's floor measured in cells came out wider than `FLARE` of
   its opening, and the pan was read as a pot, where nothing rests across its rim) or
   *open* (a cavity). A top hidden under other objects is judged from the body's outer
   wall: flaring out towards the top is a dish, else flat.

Heights, sizes and positions are in metres; the result is `SeenShape` (plain numbers and
boxes), which `utamp_gym.perception.objects` turns into a catalogue type.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import ndimage

from utamp_gym.perception.cloud import Cloud, Scene3D
from utamp_gym.perception.grid import (
    CELL,
    Grid,
    components,
    dilate_disc,
    erode_disc,
    estimate_yaw,
    footprint,
    open_disc,
    open_square,
    rotate,
)

BOX_FILL = 0.87  # opened body filling more of its bounding rectangle is a box ...
ROUND_RESIDUAL = 0.003  # m ... and so is one whose wall a circle does not fit this well
OPEN_FRACTION = 0.6  # of the largest inscribed radius: the disc that keeps only the body
MIN_MEMBER_CELLS = 12  # cells (about 1 cm^2): smaller leftovers are noise or a corner
FLAT_TOL = 0.004  # m, heights this close to the top level are on it
FLAT_FRACTION = 0.8  # of the visible top at the top level: a flat top
WELL_RATIO = 0.18  # depth / opening below this: a flat well inside a rim (tray, plate)
DISH_RATIO = 0.30  # ... below this, with a floor smaller than the opening: a dish (pan)
FLARE = 0.85  # a floor narrower than this fraction of the opening: the walls flare
DISH_FLARE = 0.12  # ... as do walls whose outer radius grows by more than this, base to top
BAR_MIDDLE = 0.6  # of a detached bar's length: its middle, clear of the posts at its ends
NECK_RISE = 0.02  # m a narrow part must stand above the body's top
NECK_AREA = 0.35  # of the body's area, at most
MARGIN = 0.05  # m of grid around an object's points
SUPPORT_TOL = 0.01  # m: a surface this close above (occlusion) or ...
SUPPORT_BELOW = 0.006  # m ... this close below the object's lowest point carries it


@dataclass(frozen=True)
class SeenBox:
    """An axis-aligned box in the seen frame."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    @property
    def size(self) -> np.ndarray:
        return np.asarray(self.hi) - np.asarray(self.lo)


@dataclass(frozen=True)
class SeenMember:
    """A member as seen: kind (body, handle), side it sticks out of, box, primitive."""

    kind: str
    side: str  # front/back/left/right for a protrusion, "on" for a part on top, "" body
    box: SeenBox
    geom: str = "box"


@dataclass(frozen=True)
class SeenTop:
    """The seen top of the body: shape, usable surface size, height and centre (seen frame),
    the rim's width (for wells and cavities) and whether it was visible at all."""

    shape: str
    size: tuple[float, float]
    height: float
    center: tuple[float, float] = (0.0, 0.0)
    rim: float = 0.0
    floor: float = 0.0  # height of the floor of a cavity or well (0: none seen)
    visible: bool = True


@dataclass(frozen=True)
class SeenShape:
    """What the fitting found (see the module docstring)."""

    yaw: float
    origin: np.ndarray  # world position of the seen frame's origin
    body: SeenMember
    members: tuple[SeenMember, ...]
    top: SeenTop
    bottom_size: tuple[float, float]  # footprint at the base (the hidden resting face)
    flare: float  # outer-wall radius growth from base to top, relative (cylinders)
    volume: float  # m^3 under the visible top surface, over the footprint
    area: float  # m^2, outer surface (body and members)
    covered: float  # fraction of the body's top hidden under other objects
    notes: tuple[str, ...] = field(default=())

    def to_world(self, local: np.ndarray) -> np.ndarray:
        """World points of seen-frame points (N, 3)."""
        xy = rotate(local[:, :2], self.yaw) + self.origin[:2]
        return np.column_stack([xy, local[:, 2] + self.origin[2]])


def _support_height(local: np.ndarray, others: np.ndarray, bg: np.ndarray, grid: Grid) -> float:
    """Height of the surface the object stands on (see the module docstring)."""
    zmin = float(np.percentile(local[:, 2], 0.5))
    foot = footprint(grid.counts(local))
    ring = dilate_disc(foot, 0.02 / grid.cell) & ~dilate_disc(foot, 1.0)
    best = -math.inf
    for pts in (others, bg):
        if not len(pts):
            continue
        top = grid.top(pts)
        ok = ring & (top <= zmin + SUPPORT_TOL) & (top > zmin - SUPPORT_BELOW)
        if ok.sum() >= 3:
            best = max(best, float(np.median(top[ok])))
    return best if best > -math.inf else zmin


def wall_fit(
    wall: np.ndarray, centre: np.ndarray, radius: float, band: float = 0.01
) -> tuple[np.ndarray, float] | None:
    """Centre and top radius of a round wall, which may flare: circles with one shared
    centre and a radius per height band of `band` m, fitted by linear least squares, the
    points farther than 4 mm from their band's circle dropped and the fit repeated; the top
    radius is the third quartile of the upper bands' points' distances (each band needs 12
    points; the largest or the 90th percentile read a 7.0 cm mug as 7.4 cm, too wide for the
    hand with the rules' clearance)."""
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
    return c, float(np.percentile(dist[upper], 75))


def _round_wall(grid: Grid, local: np.ndarray, body: np.ndarray) -> bool:
    """Whether the side wall around `body` is round: a circle fitted to its points (mid
    height, near the outline) leaves them within `ROUND_RESIDUAL` of it (a rectangle's
    wall, or a body with a handle block fused to it, does not)."""
    outline = dilate_disc(body, 5.0) & ~erode_disc(body, 5.0)
    near = _cells_of(grid, local, outline)
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


def _circle(xy: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Least-squares circle (centre, radius) through 2-D points (Kasa's method)."""
    if len(xy) < 8:
        return None
    a = np.column_stack([2 * xy, np.ones(len(xy))])
    b = (xy**2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    centre = sol[:2]
    r2 = sol[2] + centre @ centre
    return (centre, math.sqrt(r2)) if r2 > 0 else None


def _side_of(vec: np.ndarray) -> str:
    if abs(vec[0]) >= abs(vec[1]):
        return "front" if vec[0] > 0 else "back"
    return "left" if vec[1] > 0 else "right"


def _see_through(
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


def _bar_thickness(
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


def _face_beside(
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


def _between(piece: np.ndarray, bar: np.ndarray) -> np.ndarray:
    """Cells of the piece's bounding box that the trimmed bar left out (the posts' gap)."""
    i, j = np.nonzero(piece)
    box = np.zeros_like(piece)
    box[i.min() : i.max() + 1, j.min() : j.max() + 1] = True
    return box & ~dilate_disc(bar, 1.0)


def _trim_bar(piece: np.ndarray, side: str) -> tuple[np.ndarray, bool]:
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
    inner = counts[:lo] if outward else counts[hi + 1 :]
    if np.count_nonzero(inner) < 3:  # no posts (a ragged cell or two next to the body)
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


def fit_shape(cloud: Cloud, scene: Scene3D, instance: int, *, prior_yaw: float = 0.0) -> SeenShape:
    """Fit the seen geometry of object `instance` (module docstring).

    The heading comes first from the whole footprint, then from the body alone: a box's
    own rectangle, or the direction of a round body's largest protrusion (a handle sticks
    out along an axis); a round body with nothing protruding keeps `prior_yaw`."""
    yaw = estimate_yaw(cloud.points[:, :2], prior_yaw)
    shape, body_xy = _fit(cloud, scene, instance, yaw)
    if shape.body.geom == "box":
        better = estimate_yaw(body_xy, yaw) if len(body_xy) >= 5 else yaw
    else:
        sides = [m for m in shape.members if m.side != "on"]
        if sides:
            m = max(sides, key=lambda m: float(np.prod(m.box.size[:2])))
            c = (np.asarray(m.box.lo[:2]) + np.asarray(m.box.hi[:2])) / 2
            better = _snap(yaw + math.atan2(c[1], c[0]), prior_yaw)
        else:
            better = prior_yaw
    if abs(better - yaw) > math.radians(0.3):
        shape, _ = _fit(cloud, scene, instance, better)
    return shape


def _snap(angle: float, prior: float) -> float:
    """`angle` plus a multiple of 90 deg, within 45 deg of `prior`."""
    quarter = math.pi / 2
    return prior + ((angle - prior + quarter / 2) % quarter) - quarter / 2


def _fit(cloud: Cloud, scene: Scene3D, instance: int, yaw: float) -> tuple[SeenShape, np.ndarray]:
    """The seen shape at heading `yaw`, and the world xy of the body's points."""
    pts = cloud.points
    notes: list[str] = []
    c0 = pts[:, :2].mean(axis=0)

    def local_of(p: np.ndarray) -> np.ndarray:
        return np.column_stack([rotate(p[:, :2] - c0, -yaw), p[:, 2]])

    local = local_of(pts)
    lo, hi = local[:, :2].min(axis=0) - MARGIN, local[:, :2].max(axis=0) + MARGIN

    reach = float(np.max(hi - lo)) * 0.75 + MARGIN

    def near(p: np.ndarray) -> np.ndarray:
        p = p[np.all(np.abs(p[:, :2] - c0) <= reach, axis=1)] if len(p) else p
        if not len(p):
            return np.zeros((0, 3))
        q = local_of(p)
        keep = np.all((q[:, :2] >= lo) & (q[:, :2] <= hi), axis=1)
        return q[keep]

    others, bg, robot = near(scene.others(instance)), near(scene.background), near(scene.robot)
    st = scene.background_steep
    st = st[np.all(np.abs(st[:, :2] - c0) <= reach, axis=1)] if len(st) else st
    steep = np.column_stack([local_of(st[:, :3]), rotate(st[:, 3:5], -yaw), st[:, 5]])
    grid = Grid.around(local[:, :2], MARGIN)
    z0 = _support_height(local, others, bg, grid)
    local[:, 2] -= z0
    others[:, 2] -= z0
    robot[:, 2] -= z0
    counts = grid.counts(local)
    top = grid.top(local)
    other_top = grid.top(np.concatenate([others, robot]))
    # cells hidden under something above the object (another object, the robot) and inside
    # the hull of its own points belong to it: a pan's floor under a board lying on it
    # (and where no view saw the table)
    bg_counts = grid.counts(bg) if len(bg) else np.zeros(grid.shape, dtype=np.int32)
    hidden = (other_top > 0.003) & ~(top >= other_top) & (bg_counts == 0)
    if hidden.any():
        hidden &= _hull_mask(grid, local[:, :2])
    # a hole through which the table shows from above (between a tray's handle bar and its
    # rim) stays; the table seen sideways under an overhang does not count
    see_through = _see_through(grid, steep, top, counts, z0)
    seen_foot = footprint(counts) & ~see_through  # what was seen of it
    foot = footprint(counts, extra=hidden) & ~see_through  # ... and what it hides under

    # ---- body
    inscribed = ndimage.distance_transform_edt(foot)
    rmax = float(inscribed.max())
    opened = open_disc(foot, OPEN_FRACTION * rmax) if rmax > 2 else foot.copy()
    body_mask = components(opened)[0] if opened.any() else foot
    blo, bhi = grid.bounds(body_mask)
    fill = body_mask.sum() * grid.cell**2 / float(np.prod(bhi - blo))
    geom = "box" if fill > BOX_FILL or not _round_wall(grid, local, body_mask) else "cylinder"
    if geom == "box":
        sq = open_square(foot, int(OPEN_FRACTION * rmax / math.sqrt(2)))
        if sq.any():
            body_mask = components(sq)[0]
    in_body = _cells_of(grid, local, dilate_disc(body_mask, 1.0))
    body_pts = local[in_body]
    if geom == "cylinder":
        blo, bhi = grid.bounds(body_mask)
        centre, radius = (blo + bhi) / 2, float(np.mean(bhi - blo)) / 2
        zt = float(np.percentile(body_pts[:, 2], 98)) if len(body_pts) else 0.0
        near_wall = np.abs(np.linalg.norm(local[:, :2] - centre, axis=1) - radius) < 0.35 * radius
        wall = near_wall & (local[:, 2] > 0.003) & (local[:, 2] < zt - 0.002)
        fit = wall_fit(local[wall], centre, radius)
        if fit is not None:
            centre, radius = fit
        body_lo, body_hi = centre - radius, centre + radius
    else:
        xy = body_pts[:, :2] if len(body_pts) else grid.centres(body_mask)
        body_lo, body_hi = np.percentile(xy, 0.2, axis=0), np.percentile(xy, 99.8, axis=0)
        centre = (body_lo + body_hi) / 2

    # ---- heights on the body; a narrow part on top (neck)
    visible = body_mask & np.isfinite(top) & ~(other_top > top + FLAT_TOL)
    covered = 1.0 - visible.sum() / max(1, int(body_mask.sum()))
    heights = top[visible]
    neck_mask = np.zeros_like(body_mask)
    body_top = float(np.max(heights)) if len(heights) else float(local[:, 2].max())
    if len(heights) >= 10:
        level = float(np.percentile(heights, 50))  # half the body reaches this height
        high = visible & (top >= level + NECK_RISE / 2)
        if high.any() and float(heights.max()) - level >= NECK_RISE:
            piece = components(high)[0]
            outline = body_mask & ~erode_disc(body_mask, 2.0)
            inward = not (piece & outline).any()  # a neck stands inside; a rim runs round
            if inward and 4 <= piece.sum() <= NECK_AREA * visible.sum():
                hs = top[piece]
                if float(np.percentile(hs, 10)) - level >= NECK_RISE / 2:
                    neck_mask = piece
                    body_top = _body_top_below(top, visible & ~dilate_disc(piece, 1.0))
    members: list[SeenMember] = []
    if neck_mask.any():
        nlo, nhi = grid.bounds(neck_mask)
        ntop = float(top[neck_mask].max())
        nfill = neck_mask.sum() * grid.cell**2 / float(np.prod(nhi - nlo))
        members.append(
            SeenMember(
                "handle",
                "on",
                SeenBox((*nlo, body_top), (*nhi, ntop)),
                "cylinder" if nfill < BOX_FILL else "box",
            )
        )

    # ---- protruding members (handles)
    if geom == "cylinder":  # the fitted disc (a covered body's footprint is a guess)
        disc = np.linalg.norm(grid.centres(np.ones(grid.shape, bool)) - centre, axis=1)
        body_mask = (disc <= radius).reshape(grid.shape)
    rest = seen_foot & ~dilate_disc(body_mask, 2.0)
    for piece in components(rest):
        if piece.sum() < MIN_MEMBER_CELLS:
            break
        cells = grid.centres(piece)
        side = _side_of(cells.mean(axis=0) - centre)
        bar, trimmed = _trim_bar(piece, side)
        if trimmed:  # posts only if the gap between them is open above, not covered
            gap = _between(piece, bar)
            # posts need evidence: the table seen through the gap, nothing over it (a
            # handle under another object's handle shows only its sides: no posts)
            covered_gap = (gap & (other_top > 0.003)).sum() > 0.3 * max(1, int(gap.sum()))
            if covered_gap or not (see_through & gap).any():
                bar, trimmed = piece, False
        in_bar = local[_cells_of(grid, local, bar)]
        if len(in_bar) < 3:
            continue
        # the bar's extent is its points' (a cell's edge lies up to a cell beyond them: a
        # tray's 2 cm handle measured by cells came out 2.6 cm, too thick for the fingers)
        mlo, mhi = in_bar[:, :2].min(axis=0), in_bar[:, :2].max(axis=0)
        if trimmed:  # its thickness from the span between the posts (module docstring)
            mlo, mhi = _bar_thickness(in_bar, side, mlo, mhi)
        mz = in_bar[:, 2]
        zlo, zhi = float(np.percentile(mz, 1)), float(np.percentile(mz, 99))
        if not trimmed:  # an attached handle reaches the body's box
            ax = 0 if side in ("front", "back") else 1
            if geom == "box":  # the body's face from its points beside the handle
                _face_beside(body_pts, side, mlo[1 - ax], mhi[1 - ax], body_lo, body_hi)
            if side in ("back", "right"):
                mhi[ax] = body_lo[ax]
            else:
                mlo[ax] = body_hi[ax]
        members.append(SeenMember("handle", side, SeenBox((*mlo, max(zlo, 0.0)), (*mhi, zhi))))

    if geom == "box":
        centre = (body_lo + body_hi) / 2

    # ---- top surface of the body
    top_shape = _top(
        grid,
        top,
        visible & ~dilate_disc(neck_mask, 1.0),
        body_mask,
        body_top,
        geom,
        body_lo,
        body_hi,
    )
    if geom == "cylinder" and top_shape.visible and top_shape.shape in ("open", "concave"):
        top_shape = _round_opening(top_shape, local[in_body], centre, radius)
    elif geom == "box" and top_shape.visible and top_shape.rim > 0:
        top_shape = _box_opening(top_shape, local[in_body], body_lo, body_hi, body_top)
    flare = _flare(local[in_body], centre, body_top) if geom == "cylinder" else 0.0
    if top_shape.shape == "open" and flare > DISH_FLARE and top_shape.floor > 0:
        depth = top_shape.height - top_shape.floor
        if depth < DISH_RATIO * float(np.mean(top_shape.size)):  # a shallow flared cavity
            top_shape = replace(top_shape, shape="concave")
    if not top_shape.visible:
        shape = "concave" if flare > DISH_FLARE else "flat"
        size = tuple((body_hi - body_lo).tolist())
        mid = tuple(((body_hi + body_lo) / 2).tolist())  # the body's: `_moved_top` shifts it
        top_shape = SeenTop(shape, size, body_top, mid, visible=False)  # type: ignore[arg-type]
        notes.append("top hidden under other objects: judged from the outer wall")
    bottom = _bottom_size(local[in_body], centre, geom, body_lo, body_hi)

    # ---- the seen frame: origin at the body's footprint centre on the support
    origin_xy = rotate(centre[None, :], yaw)[0] + c0
    shift = np.array([*centre, 0.0])

    def moved(b: SeenBox) -> SeenBox:
        return SeenBox(
            tuple((np.asarray(b.lo) - shift).tolist()), tuple((np.asarray(b.hi) - shift).tolist())
        )  # type: ignore[arg-type]

    body = SeenMember("body", "", moved(SeenBox((*body_lo, 0.0), (*body_hi, body_top))), geom)
    members = [SeenMember(m.kind, m.side, moved(m.box), m.geom) for m in members]
    top_shape = _moved_top(top_shape, centre)
    volume = (
        float(np.sum(np.clip(np.where(foot & np.isfinite(top), top, 0.0), 0.0, None)))
        * grid.cell**2
    )
    area = _surface_area(body, members)
    body_xy = rotate(body_pts[:, :2], yaw) + c0
    shape = SeenShape(
        yaw=yaw,
        origin=np.array([*origin_xy, z0]),
        body=body,
        members=tuple(members),
        top=top_shape,
        bottom_size=bottom,
        flare=flare,
        volume=volume,
        area=area,
        covered=float(covered),
        notes=tuple(notes),
    )
    return shape, body_xy


def _hull_mask(grid: Grid, xy: np.ndarray) -> np.ndarray:
    """Cells whose centres lie inside the convex hull of `xy`."""
    from scipy.spatial import ConvexHull, QhullError

    out = np.zeros(grid.shape, dtype=bool)
    try:
        hull = ConvexHull(xy)
    except (QhullError, ValueError):
        return out
    ii, jj = np.meshgrid(np.arange(grid.shape[0]), np.arange(grid.shape[1]), indexing="ij")
    centres = grid.lo + (np.stack([ii.ravel(), jj.ravel()], axis=1) + 0.5) * grid.cell
    inside = np.all(centres @ hull.equations[:, :2].T + hull.equations[:, 2] <= 1e-9, axis=1)
    return inside.reshape(grid.shape)


def _cells_of(grid: Grid, pts: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Which points fall into the cells of `mask`."""
    i, j, inside = grid.index(pts[:, :2])
    out = np.zeros(len(pts), dtype=bool)
    out[inside] = mask[i[inside], j[inside]]
    return out


def _body_top_below(top: np.ndarray, region: np.ndarray) -> float:
    hs = top[region & np.isfinite(top)]
    return float(np.percentile(hs, 95)) if len(hs) else 0.0


def _top(
    grid: Grid,
    top: np.ndarray,
    visible: np.ndarray,
    body: np.ndarray,
    level: float,
    geom: str,
    lo: np.ndarray,
    hi: np.ndarray,
) -> SeenTop:
    """The body's top surface (module docstring, step 5)."""
    full = tuple((hi - lo).tolist())
    centre = tuple(((hi + lo) / 2).tolist())
    if visible.sum() < max(8, 0.15 * body.sum()):
        return SeenTop("flat", full, level, centre, visible=False)  # type: ignore[arg-type]
    hs = top[visible]
    rim_level = float(np.percentile(hs, 95))
    at_top = visible & (top >= rim_level - FLAT_TOL)
    share = at_top.sum() / visible.sum()
    if share >= FLAT_FRACTION:
        return SeenTop("flat", full, rim_level, centre)  # type: ignore[arg-type]
    # the rim: top-level cells connected to the body's outline
    outline = body & ~erode_disc(body, 1.5)
    rim = np.zeros_like(body)
    for piece in components(at_top):
        if (piece & dilate_disc(outline, 1.0)).any():
            rim |= piece
    inside = body & ~rim & ~dilate_disc(outline & ~rim, 0.0)
    inner = components(inside)[0] if inside.any() else inside
    if not _has_ring(rim, body):  # no rim around a lower inside: a dome
        return SeenTop("round", full, rim_level, centre)  # type: ignore[arg-type]
    if not inner.any():
        return SeenTop("flat", full, rim_level, centre)  # type: ignore[arg-type]
    ilo, ihi = grid.bounds(inner)
    opening = ihi - ilo
    width = float(min(opening)) if geom == "box" else float(np.mean(opening))
    seen = inner & np.isfinite(top)
    floor_hs = top[seen]
    rim_width = float(np.mean((hi - lo) - opening)) / 2
    if len(floor_hs) < 0.3 * inner.sum():  # mostly unseen inside: a deep cavity
        size = tuple(opening.tolist()) if geom == "box" else (width, width)
        return SeenTop("open", size, rim_level, tuple(((ilo + ihi) / 2).tolist()), rim_width)  # type: ignore[arg-type]
    floor = float(np.percentile(floor_hs, 20))
    plateau = seen & (np.abs(top - floor) <= FLAT_TOL)
    depth = rim_level - floor
    ratio = depth / max(width, 1e-6)
    if ratio < WELL_RATIO and plateau.sum() >= 0.6 * seen.sum():
        plo, phi = grid.bounds(components(plateau)[0])
        return SeenTop(
            "flat",
            tuple((phi - plo).tolist()),  # type: ignore[arg-type]
            floor,
            tuple(((plo + phi) / 2).tolist()),  # type: ignore[arg-type]
            rim_width,
            floor,
        )
    pl = components(plateau)[0] if plateau.any() else plateau
    if plateau.any():
        plo, phi = grid.bounds(pl)
        floor_width = float(np.mean(phi - plo))
    else:
        floor_width = 0.0
    size = tuple(opening.tolist()) if geom == "box" else (width, width)
    if ratio < DISH_RATIO and floor_width < FLARE * width:
        return SeenTop(
            "concave", size, rim_level, tuple(((ilo + ihi) / 2).tolist()), rim_width, floor
        )  # type: ignore[arg-type]
    return SeenTop("open", size, rim_level, tuple(((ilo + ihi) / 2).tolist()), rim_width, floor)  # type: ignore[arg-type]


def _round_opening(top: SeenTop, pts: np.ndarray, centre: np.ndarray, radius: float) -> SeenTop:
    """A round opening's diameter from the inner edge of the rim's top (finer than cells)."""
    r = np.linalg.norm(pts[:, :2] - centre, axis=1)
    rim = (pts[:, 2] >= top.height - 0.003) & (r >= 0.5 * radius) & (r <= radius + 0.003)
    if rim.sum() < 10:
        return top
    inner = float(np.percentile(r[rim], 2))
    d = 2 * min(inner, radius)
    return SeenTop(
        top.shape, (d, d), top.height, top.center, radius - inner, top.floor, top.visible
    )


def _box_opening(
    top: SeenTop, pts: np.ndarray, lo: np.ndarray, hi: np.ndarray, level: float
) -> SeenTop:
    """A box's opening or well from the inner edges of its rim's top on each side (finer
    than cells; objects standing in the well do not shrink it)."""
    rim = pts[pts[:, 2] >= level - 0.003]
    size, mid = hi - lo, (hi + lo) / 2
    inner = []
    for ax in (0, 1):
        other = 1 - ax
        across = np.abs(rim[:, other] - mid[other]) <= 0.25 * size[other]
        edges = []
        for sign in (1.0, -1.0):
            near = across & (sign * (rim[:, ax] - mid[ax]) >= 0.25 * size[ax])
            if near.sum() < 5:
                return top
            d = sign * (rim[near, ax] - mid[ax])
            edges.append(_inner_edge(d, rim[near, other]))
        inner.append(edges)
    opening = (inner[0][0] + inner[0][1], inner[1][0] + inner[1][1])
    centre = (
        float(mid[0] + (inner[0][0] - inner[0][1]) / 2),
        float(mid[1] + (inner[1][0] - inner[1][1]) / 2),
    )
    rim_width = float(np.mean(size - np.asarray(opening))) / 2
    return SeenTop(top.shape, opening, top.height, centre, rim_width, top.floor, top.visible)


def _inner_edge(dist: np.ndarray, along: np.ndarray, step: float = 0.01) -> float:
    """Distance of a rim's straight inner edge from the centre: the nearest point in each
    `step` of its length, their median (the nearest of all, 1st percentile, took the
    inward end of an edge tilted by the heading's error: a tray's well 1 mm narrow)."""
    bins = np.floor(along / step).astype(int)
    nearest = [float(dist[bins == b].min()) for b in np.unique(bins) if (bins == b).sum() >= 3]
    return float(np.median(nearest)) if len(nearest) >= 3 else float(np.percentile(dist, 1))


def _has_ring(rim: np.ndarray, body: np.ndarray) -> bool:
    """True if the top-level cells run around most of the body's outline (a rim)."""
    outline = body & ~erode_disc(body, 1.5)
    return bool(outline.any()) and (rim & dilate_disc(outline, 1.0)).sum() >= 0.5 * outline.sum()


def _moved_top(t: SeenTop, centre: np.ndarray) -> SeenTop:
    c = (t.center[0] - float(centre[0]), t.center[1] - float(centre[1]))
    return SeenTop(t.shape, t.size, t.height, c, t.rim, t.floor, t.visible)


def _flare(pts: np.ndarray, centre: np.ndarray, top: float) -> float:
    """Relative growth of the outer radius from the base to the top (a dish flares)."""
    if len(pts) < 20 or top <= 0.01:
        return 0.0
    r = np.linalg.norm(pts[:, :2] - centre, axis=1)
    z = pts[:, 2]
    low = r[(z > 0.002) & (z < 0.25 * top)]
    high = r[(z > 0.75 * top) & (z < top - 0.002)]
    if len(low) < 5 or len(high) < 5:
        return 0.0
    rl, rh = float(np.percentile(low, 95)), float(np.percentile(high, 95))
    return (rh - rl) / max(rh, 1e-6)


def _bottom_size(
    pts: np.ndarray, centre: np.ndarray, geom: str, lo: np.ndarray, hi: np.ndarray
) -> tuple[float, float]:
    """Extent of the body's base (the face it rests on, never seen): the lowest slice of
    its side wall (a flared pan stands on a smaller floor), else the footprint."""
    full = tuple((hi - lo).tolist())
    if geom != "cylinder" or len(pts) < 20:
        return full  # type: ignore[return-value]
    z = pts[:, 2]
    low = pts[(z > 0.001) & (z < 0.012)]
    if len(low) < 8:
        return full  # type: ignore[return-value]
    r = float(np.percentile(np.linalg.norm(low[:, :2] - centre, axis=1), 95))
    d = min(2 * r, float(np.mean(hi - lo)))
    return (d, d)


def _surface_area(body: SeenMember, members: list[SeenMember]) -> float:
    """Outer surface area (m^2) of the body (a cylinder or box) and the member boxes."""
    s = body.box.size
    if body.geom == "cylinder":
        r = float(np.mean(s[:2])) / 2
        area = 2 * math.pi * r * s[2] + 2 * math.pi * r * r
    else:
        area = 2 * (s[0] * s[1] + s[0] * s[2] + s[1] * s[2])
    for m in members:
        a = m.box.size
        area += 2 * (a[0] * a[1] + a[0] * a[2] + a[1] * a[2])
    return float(area)


__all__ = ["CELL", "SeenBox", "SeenMember", "SeenShape", "SeenTop", "fit_shape", "wall_fit"]
