"""The top surface of an object's body, in its seen frame (`shape`), from its visible heights.

Cells covered by other objects are left out. The top is *flat* (at least `FLAT_FRACTION` of
it within `FLAT_TOL` of one height), *round* (lower towards its outline all around: a dome),
or lower inside than at a rim running round it: a *flat* well inside a rim when shallow
(depth below `WELL_RATIO` of the opening, or below `DEEP_WELL_RATIO` where the floor spans
the opening and the outer wall does not flare: a deep plate), *concave* (a dish whose walls
flare from a smaller floor, or whose outer wall flares by more than `DISH_FLARE`: a pan's
floor measured in cells came out wider than `FLARE` of its opening, and the pan was read as
a pot, where nothing rests across its rim; a flared body whose rim is a wall's edge, thinner
than `THIN_WALL`, is never a flat well: a shallow pan is no plate) or *open* (a cavity; an
inside mostly unseen within a rim lower than `WELL_RATIO` of its width is a well under what
lies in it, a tray's under a board). A rim that reaches the top level along too little of
the outline to run round it still makes a well when the inside lies lower than the outline
band (a large plate's rim seen to its edge in places); a dome is higher inside. A round
well one side of which is hidden is as wide as its widest extent. An opening is measured
finer than cells, from the inner edge of the rim's top; the base (never seen) from the
lowest slice of the side wall; its flare (`wall_flare`) judges a top hidden under other
objects, and a flared cavity shallower than `FLARED_DISH_RATIO` of its opening is a dish
(`shape`).
"""

from __future__ import annotations

import numpy as np

from utamp_gym.perception.grid import Grid, components, dilate_disc, erode_disc
from utamp_gym.perception.seen import SeenTop

FLAT_TOL = 0.004  # m, heights this close to the top level are on it
FLAT_FRACTION = 0.8  # of the visible top at the top level: a flat top
WELL_RATIO = 0.18  # depth / opening below this: a flat well inside a rim (tray, plate)
DEEP_WELL_RATIO = 0.25  # ... or below this with a floor spanning the opening (a deep plate)
DISH_RATIO = 0.30  # ... below this, with a floor smaller than the opening: a dish (pan)
FLARE = 0.85  # a floor narrower than this fraction of the opening: the walls flare
#: ... as do walls whose outer radius grows by more than this, base to top. On train, plates
#: measure 0.009-0.045, bowls, cups and pots below 0.04, frying pans 0.12-0.27; under a board
#: or a plate that hides their upper wall, pans measured 0.09-0.11 (six-object scenes of the
#: train families drawn with seeds outside every split), and 0.12 read those tops as flat
DISH_FLARE = 0.08
#: a flared cavity shallower than this fraction of its opening is a dish: frying pans are up
#: to 60 mm deep on 173 mm openings (0.35; `DISH_RATIO` read the deepest as pots)
FLARED_DISH_RATIO = 0.36
#: m, a rim narrower than this is a wall's edge (a pan's: 3-5 mm), not a plate's ledge (25-40
#: mm on train): a flared body with such a rim is a dish however shallow (a frying pan's floor
#: 16-18 % of its opening deep was read as a plate's well, train/0117)
THIN_WALL = 0.012


def body_top_below(top: np.ndarray, region: np.ndarray) -> float:
    hs = top[region & np.isfinite(top)]
    return float(np.percentile(hs, 95)) if len(hs) else 0.0


def classify_top(
    grid: Grid,
    top: np.ndarray,
    visible: np.ndarray,
    body: np.ndarray,
    level: float,
    geom: str,
    lo: np.ndarray,
    hi: np.ndarray,
    over: np.ndarray | None = None,
    flared: bool = False,
) -> SeenTop:
    """The body's top surface (module docstring). `over`: cells where another object stands
    above the body's top: a cavity or dish whose inside is mostly under them was not seen,
    it is hidden (a tumbler standing on an inverted mug's base left a ring around it, read
    as an opening); a flat well shows around what stands in it (a pan in a tray). `flared`:
    the outer wall flares (by more than `DISH_FLARE`): a pan, never a deep well."""
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
    if not _has_ring(rim, body) and not _lower_inside(top, visible, body):  # a dome
        return SeenTop("round", full, rim_level, centre)  # type: ignore[arg-type]
    if not inner.any():
        return SeenTop("flat", full, rim_level, centre)  # type: ignore[arg-type]
    hidden = over is not None and (inner & over).sum() >= 0.5 * inner.sum()
    out = _inside(grid, top, inner, geom, rim_level, lo, hi, flared)
    if hidden and out.shape in ("open", "concave"):  # no cavity seen: one under an object
        return SeenTop("flat", full, rim_level, centre, visible=False)  # type: ignore[arg-type]
    return out


def _inside(
    grid: Grid,
    top: np.ndarray,
    inner: np.ndarray,
    geom: str,
    rim_level: float,
    lo: np.ndarray,
    hi: np.ndarray,
    flared: bool = False,
) -> SeenTop:
    """What lies inside a rim: a flat well, a dish (concave) or a cavity (open)."""
    ilo, ihi = grid.bounds(inner)
    opening = ihi - ilo
    width = float(min(opening)) if geom == "box" else float(np.mean(opening))
    seen = inner & np.isfinite(top)
    floor_hs = top[seen]
    rim_width = float(np.mean((hi - lo) - opening)) / 2
    if len(floor_hs) < 0.3 * inner.sum():  # mostly unseen inside: a deep cavity
        size = tuple(opening.tolist()) if geom == "box" else (width, width)
        mid = tuple(((ilo + ihi) / 2).tolist())
        if rim_level < WELL_RATIO * width and len(floor_hs) >= 8:
            # unless too shallow to be one: a well under what stands in it (a tray under a
            # board lying in it, whose top is no higher than the tray's rim)
            floor = float(np.percentile(floor_hs, 20))
            return SeenTop("flat", size, floor, mid, rim_width, floor)  # type: ignore[arg-type]
        return SeenTop("open", size, rim_level, mid, rim_width)  # type: ignore[arg-type]
    floor = float(np.percentile(floor_hs, 20))
    plateau = seen & (np.abs(top - floor) <= FLAT_TOL)
    depth = rim_level - floor
    ratio = depth / max(width, 1e-6)
    pl = components(plateau)[0] if plateau.any() else plateau
    if plateau.any():
        plo, phi = grid.bounds(pl)
        floor_width = float(np.mean(phi - plo))
    else:
        floor_width = 0.0
    level = plateau.sum() >= 0.6 * seen.sum()  # mostly one flat floor
    steep = floor_width >= FLARE * width and not flared  # no flared walls, inside or out
    pan = flared and rim_width < THIN_WALL  # a flared wall's edge around it, no ledge
    if level and not pan and (ratio < WELL_RATIO or (ratio < DEEP_WELL_RATIO and steep)):
        well, mid = phi - plo, (plo + phi) / 2
        if geom == "cylinder" and abs(well[0] - well[1]) > 2 * grid.cell:
            # a round well one of whose sides is hidden (a glass standing at its edge): as
            # wide as its widest extent, centred on the body across the hidden side
            well = np.full(2, well.max())
            short = int(np.argmin(phi - plo))
            mid[short] = (lo[short] + hi[short]) / 2
        return SeenTop(
            "flat",
            tuple(well.tolist()),  # type: ignore[arg-type]
            floor,
            tuple(mid.tolist()),  # type: ignore[arg-type]
            rim_width,
            floor,
        )
    size = tuple(opening.tolist()) if geom == "box" else (width, width)
    if ratio < DISH_RATIO and floor_width < FLARE * width:
        return SeenTop(
            "concave", size, rim_level, tuple(((ilo + ihi) / 2).tolist()), rim_width, floor
        )  # type: ignore[arg-type]
    return SeenTop("open", size, rim_level, tuple(((ilo + ihi) / 2).tolist()), rim_width, floor)  # type: ignore[arg-type]


def round_opening(top: SeenTop, pts: np.ndarray, centre: np.ndarray, radius: float) -> SeenTop:
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


def box_opening(
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


def _lower_inside(top: np.ndarray, visible: np.ndarray, body: np.ndarray) -> bool:
    """True if the body's core (beyond half its radius from the outline) lies lower than its
    outline band, by more than twice `FLAT_TOL`: a well inside a rim that reaches the top
    level along too little of the outline to be a ring (a large plate's sloped rim, a third
    of it or less); a dome is higher inside."""
    radius = float(np.sqrt(body.sum() / np.pi))  # cells
    core = visible & erode_disc(body, 0.5 * radius)
    band = visible & ~erode_disc(body, max(1.5, 0.2 * radius))
    if core.sum() < 8 or band.sum() < 8:
        return False
    return float(np.median(top[core])) < float(np.median(top[band])) - 2 * FLAT_TOL


def moved_top(t: SeenTop, centre: np.ndarray) -> SeenTop:
    c = (t.center[0] - float(centre[0]), t.center[1] - float(centre[1]))
    return SeenTop(t.shape, t.size, t.height, c, t.rim, t.floor, t.visible)


def wall_flare(pts: np.ndarray, centre: np.ndarray, top: float) -> float:
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


def bottom_size(
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


__all__ = [
    "body_top_below",
    "bottom_size",
    "box_opening",
    "classify_top",
    "moved_top",
    "round_opening",
    "wall_flare",
]
