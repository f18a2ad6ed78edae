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
   at least `MIN_MEMBER_CELLS` is a handle on the side it sticks out of (`members`: a bar
   held away from the body by posts is trimmed to the bar). A narrow part standing on top
   of the body (a bottle's neck) is found from the heights: a plateau of less than half the
   body's area at least `NECK_RISE` above the rest;
5. **top** — the shape of the body's top from its visible heights: flat, round, concave or
   open (`tops`). A top hidden under other objects is judged from the body's outer wall:
   flaring out towards the top (more than `tops.DISH_FLARE`) is a dish, else flat.

Heights, sizes and positions are in metres; the result is `SeenShape` (`seen`: plain
numbers and boxes), which `utamp_gym.perception.objects` turns into a catalogue type.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import ndimage

from utamp_gym.perception.cloud import Cloud, Scene3D
from utamp_gym.perception.grid import (
    CELL,
    Grid,
    cells_of,
    components,
    dilate_disc,
    erode_disc,
    estimate_yaw,
    footprint,
    open_disc,
    open_square,
    rotate,
)
from utamp_gym.perception.members import (
    bar_thickness,
    between,
    face_beside,
    side_of,
    table_seen_through,
    trim_bar,
)
from utamp_gym.perception.seen import SeenBox, SeenMember, SeenShape, SeenTop
from utamp_gym.perception.tops import (
    DISH_FLARE,
    FLARED_DISH_RATIO,
    FLAT_TOL,
    body_top_below,
    bottom_size,
    box_opening,
    classify_top,
    moved_top,
    round_opening,
    wall_flare,
)
from utamp_gym.perception.walls import round_wall, wall_fit, widen_to_arc

BOX_FILL = 0.87  # opened body filling more of its bounding rectangle is a box (or one
#: whose wall is not round: `walls.ROUND_RESIDUAL`)
OPEN_FRACTION = 0.6  # of the largest inscribed radius: the disc that keeps only the body
#: ... and the half side of a box's square (a spatula's grip, 0.45 of its blade's width,
#: survived a square of 0.42 of the blade's width and was read as part of it)
SQUARE_FRACTION = 0.75
MIN_MEMBER_CELLS = 12  # cells (about 1 cm^2): smaller leftovers are noise or a corner
NECK_RISE = 0.02  # m a narrow part must stand above the body's top
NECK_AREA = 0.45  # of the seen top's cells, at most (a cell-quantised neck reads wider)
MARGIN = 0.05  # m of grid around an object's points
SUPPORT_TOL = 0.01  # m: a surface this close above (occlusion) or ...
SUPPORT_BELOW = 0.006  # m ... this close below the object's lowest point carries it


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
    rays_xy = rotate(cloud.rays[:, :2], -yaw)  # viewing directions in the seen frame
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
    see_through = table_seen_through(grid, steep, top, counts, z0)
    seen_foot = footprint(counts) & ~see_through  # what was seen of it
    foot = footprint(counts, extra=hidden) & ~see_through  # ... and what it hides under

    # ---- body
    inscribed = ndimage.distance_transform_edt(foot)
    rmax = float(inscribed.max())
    opened = open_disc(foot, OPEN_FRACTION * rmax) if rmax > 2 else foot.copy()
    body_mask = components(opened)[0] if opened.any() else foot
    blo, bhi = grid.bounds(body_mask)
    fill = body_mask.sum() * grid.cell**2 / float(np.prod(bhi - blo))
    geom = "box" if fill > BOX_FILL or not round_wall(grid, local, body_mask) else "cylinder"
    if geom == "box":
        sq = open_square(foot, int(SQUARE_FRACTION * rmax))
        if sq.any():
            body_mask = components(sq)[0]
    in_body = cells_of(grid, local, dilate_disc(body_mask, 1.0))
    body_pts = local[in_body]
    if geom == "cylinder":
        blo, bhi = grid.bounds(body_mask)
        centre, radius = (blo + bhi) / 2, float(np.mean(bhi - blo)) / 2
        zt = float(np.percentile(body_pts[:, 2], 98)) if len(body_pts) else 0.0
        near_wall = np.abs(np.linalg.norm(local[:, :2] - centre, axis=1) - radius) < 0.35 * radius
        wall = near_wall & (local[:, 2] > 0.003) & (local[:, 2] < zt - 0.002)
        fit = wall_fit(local[wall], centre, radius, rays=rays_xy[wall])
        if fit is not None:
            centre, radius = fit
        centre, radius = widen_to_arc(grid, seen_foot, centre, radius)
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
                    body_top = body_top_below(top, visible & ~dilate_disc(piece, 1.0))
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
    attached = np.zeros_like(body_mask)  # the attached handles' cells
    for piece in components(rest):
        if piece.sum() < MIN_MEMBER_CELLS:
            break
        cells = grid.centres(piece)
        side = side_of(cells.mean(axis=0) - centre)
        bar, trimmed = trim_bar(piece, side)
        if trimmed:  # posts only if the gap between them is open above, not covered
            gap = between(piece, bar)
            # posts need evidence: the table seen through the gap, nothing over it (a
            # handle under another object's handle shows only its sides: no posts)
            covered_gap = (gap & (other_top > 0.003)).sum() > 0.3 * max(1, int(gap.sum()))
            if covered_gap or not (see_through & gap).any():
                bar, trimmed = piece, False
        in_bar = local[cells_of(grid, local, bar)]
        if len(in_bar) < 3:
            continue
        # the bar's extent is its points' (a cell's edge lies up to a cell beyond them: a
        # tray's 2 cm handle measured by cells came out 2.6 cm, too thick for the fingers)
        mlo, mhi = in_bar[:, :2].min(axis=0), in_bar[:, :2].max(axis=0)
        if trimmed:  # its thickness from the span between the posts (`members`)
            mlo, mhi = bar_thickness(in_bar, side, mlo, mhi)
        mz = in_bar[:, 2]
        zlo, zhi = float(np.percentile(mz, 1)), float(np.percentile(mz, 99))
        if not trimmed:  # an attached handle reaches the body's box
            attached |= piece
            ax = 0 if side in ("front", "back") else 1
            if geom == "box":  # the body's face from its points beside the handle
                face_beside(body_pts, side, mlo[1 - ax], mhi[1 - ax], body_lo, body_hi)
            if side in ("back", "right"):
                mhi[ax] = body_lo[ax]
            else:
                mlo[ax] = body_hi[ax]
        members.append(SeenMember("handle", side, SeenBox((*mlo, max(zlo, 0.0)), (*mhi, zhi))))

    if geom == "box":
        centre = (body_lo + body_hi) / 2
    if attached.any() and not neck_mask.any():  # a handle rising above the body (a
        # spatula's grip over its blade) leaves its root's heights in the body's cells
        away = top[visible & ~dilate_disc(attached, 5.0)]
        if len(away) >= 10 and float(np.percentile(away, 98)) < body_top - 0.003:
            body_top = float(np.percentile(away, 98))

    # ---- top surface of the body
    flare = wall_flare(local[in_body], centre, body_top) if geom == "cylinder" else 0.0
    top_shape = classify_top(
        grid,
        top,
        visible & ~dilate_disc(neck_mask, 1.0),
        body_mask,
        body_top,
        geom,
        body_lo,
        body_hi,
        over=other_top > body_top + FLAT_TOL,
        flared=flare > DISH_FLARE,
    )
    if geom == "cylinder" and top_shape.visible and top_shape.shape in ("open", "concave"):
        top_shape = round_opening(top_shape, local[in_body], centre, radius)
    elif geom == "box" and top_shape.visible and top_shape.rim > 0:
        top_shape = box_opening(top_shape, local[in_body], body_lo, body_hi, body_top)
    if top_shape.shape == "open" and flare > DISH_FLARE and top_shape.floor > 0:
        depth = top_shape.height - top_shape.floor
        if depth < FLARED_DISH_RATIO * float(np.mean(top_shape.size)):  # a flared dish
            top_shape = replace(top_shape, shape="concave")
    if not top_shape.visible:
        shape = "concave" if flare > DISH_FLARE else "flat"
        size = tuple((body_hi - body_lo).tolist())
        mid = tuple(((body_hi + body_lo) / 2).tolist())  # the body's: `moved_top` shifts it
        top_shape = SeenTop(shape, size, body_top, mid, visible=False)  # type: ignore[arg-type]
        notes.append("top hidden under other objects: judged from the outer wall")
    bottom = bottom_size(local[in_body], centre, geom, body_lo, body_hi)

    # ---- the seen frame: origin at the body's footprint centre on the support
    origin_xy = rotate(centre[None, :], yaw)[0] + c0
    shift = np.array([*centre, 0.0])

    def moved(b: SeenBox) -> SeenBox:
        return SeenBox(
            tuple((np.asarray(b.lo) - shift).tolist()), tuple((np.asarray(b.hi) - shift).tolist())
        )  # type: ignore[arg-type]

    body = SeenMember("body", "", moved(SeenBox((*body_lo, 0.0), (*body_hi, body_top))), geom)
    members = [SeenMember(m.kind, m.side, moved(m.box), m.geom) for m in members]
    top_shape = moved_top(top_shape, centre)
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
