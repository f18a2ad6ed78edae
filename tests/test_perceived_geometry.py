"""The perceiver's geometric readings that the rules decide at the millimetre: round walls
measured on their outer face, rims that end where the well inside them begins, the faces no
camera sees, a plate's mass (`perception.walls`, `perception.objects`, `perception.tops`)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from utamp_gym.affordances.solids import stand_refusal
from utamp_gym.perception.grid import Grid
from utamp_gym.perception.material import MaterialEstimate, estimate_mass
from utamp_gym.perception.members import trim_bar
from utamp_gym.perception.objects import RIM_BAND, PerceivedObject, _edges, bare_slab
from utamp_gym.perception.seen import SeenBox, SeenMember, SeenShape, SeenTop
from utamp_gym.perception.tops import classify_top
from utamp_gym.perception.volumes import mass_area, mass_areas, shell_area, slab, solid_volume
from utamp_gym.perception.walls import wall_fit
from utamp_gym.scene.materials import material


def _ring(radius: float, n: int = 720, heights: tuple[float, ...] = (0.05, 0.06, 0.07)):
    phi = np.linspace(0, 2 * math.pi, n, endpoint=False)
    pts = [np.column_stack([radius * np.cos(phi), radius * np.sin(phi), np.full(n, z)])
           for z in heights]  # fmt: skip
    return np.concatenate(pts)


def test_a_round_wall_is_measured_on_its_outer_face() -> None:
    """A 7.2 cm tumbler with a 3 mm wall whose inner face is seen over the rim: the rays
    tell the outer face (seen from outside) from the inner one."""
    outer, inner = _ring(0.036), _ring(0.033, n=360)
    wall = np.concatenate([outer, inner])
    rays = np.concatenate([-outer[:, :2] / 0.036, inner[:, :2] / 0.033])  # towards / away
    rays = np.column_stack([rays, np.full(len(rays), -0.5)])
    _, r = wall_fit(wall, np.zeros(2), 0.036, rays=rays)
    assert r == pytest.approx(0.036, abs=2e-4)


def test_a_flared_wall_is_measured_at_its_top() -> None:
    """A pan's wall widening 4 mm per centimetre of height: the radius at its top."""
    heights = (0.005, 0.015, 0.025, 0.035, 0.045)
    wall = np.concatenate([_ring(0.08 + 0.4 * z, heights=(z,)) for z in heights])
    rays = np.column_stack([-wall[:, :2] / np.linalg.norm(wall[:, :2], axis=1)[:, None],
                            np.full(len(wall), -0.5)])  # fmt: skip
    _, r = wall_fit(wall, np.zeros(2), 0.09, rays=rays)
    assert r == pytest.approx(0.08 + 0.4 * 0.045, abs=1e-3)


def _rimmed(geom: str, handles: tuple[SeenMember, ...] = ()) -> SeenShape:
    """A 40 x 30 cm tray (or a 21 cm plate) 4 cm high with a well 1.5 cm deep in a 1.5 cm
    rim, the well 2 mm off centre along x."""
    size = (0.4, 0.3) if geom == "box" else (0.21, 0.21)
    lo, hi = (-size[0] / 2, -size[1] / 2, 0.0), (size[0] / 2, size[1] / 2, 0.04)
    body = SeenMember("body", "", SeenBox(lo, hi), geom)
    well = (size[0] - 0.03, size[1] - 0.03)
    top = SeenTop("flat", well, 0.015, (0.002, 0.0), 0.015, 0.015)
    return SeenShape(0.0, np.zeros(3), body, handles, top, size, 0.0, 0.001, 0.3, 0.0)


def test_a_trays_rims_stand_on_the_table_and_end_at_its_well() -> None:
    front = SeenMember("handle", "front", SeenBox((0.22, -0.06, 0.02), (0.24, 0.06, 0.04)))
    back = SeenMember("handle", "back", SeenBox((-0.24, -0.06, 0.02), (-0.22, 0.06, 0.04)))
    bars = (front, back)
    edges = _edges(_rimmed("box", bars))  # offered whatever the tray weighs
    assert [e.side for e in edges] == ["left", "right"]
    left = edges[0].box
    assert left.lo[2] == 0.0  # from the table up, as the catalogues declare a tray's rims
    assert left.lo[1] == pytest.approx(0.15 - 0.015)  # where the well ends


def test_a_plates_rim_ends_where_its_off_centre_well_begins() -> None:
    front, back = _edges(_rimmed("cylinder"))
    assert (front.side, back.side) == ("front", "back")
    assert front.box.lo[0] == pytest.approx(0.002 + 0.09)  # the well's edge, not r - rim
    assert back.box.hi[0] == pytest.approx(0.002 - 0.09)
    assert front.box.lo[2] == pytest.approx(0.015)  # the band starts at the well's floor


def test_round_rims_take_the_catalogues_span_and_band() -> None:
    """A plate's rim strips span 0.3 of its radius either side (at most 4 cm) from its well
    up; a bowl's (an open top) 0.4 of it, in a band `RIM_BAND` deep below the rim."""
    front, _ = _edges(_rimmed("cylinder"))  # a 21 cm plate
    assert front.box.hi[1] - front.box.lo[1] == pytest.approx(2 * 0.3 * 0.105)
    plate = _rimmed("cylinder")
    bowl = replace(plate, top=replace(plate.top, shape="open", floor=0.005))
    front, back = _edges(bowl)
    assert front.box.hi[1] - front.box.lo[1] == pytest.approx(2 * 0.04)  # 0.4 r > 4 cm
    assert front.box.lo[2] == pytest.approx(0.04 - RIM_BAND)  # not from the floor
    assert back.box.hi[2] == pytest.approx(0.04)
    small = replace(
        bowl, body=replace(bowl.body, box=SeenBox((-0.06, -0.06, 0.0), (0.06, 0.06, 0.04)))
    )
    front, _ = _edges(small)
    assert front.box.hi[1] - front.box.lo[1] == pytest.approx(2 * 0.4 * 0.06)


def _handle_piece(post_slices: int, gap: int = 0) -> np.ndarray:
    """Cells of a tray's front handle seen from above (rows: outward, x; columns: along
    the bar): a bar 6 rows x 36 columns and `post_slices` rows of two 3-cell posts at its
    ends (`gap`: columns between two runs of a narrow piece, instead of posts)."""
    piece = np.zeros((6 + post_slices, 40), dtype=bool)
    piece[post_slices:, 2:38] = True
    for r in range(post_slices):
        if gap:
            piece[r, 10:13] = piece[r, 13 + gap : 16 + gap] = True
        else:
            piece[r, 2:5] = piece[r, 35:38] = True
    return piece


def test_a_bar_on_posts_is_trimmed_even_where_a_narrow_gap_shows_one_slice_of_posts() -> None:
    bar, trimmed = trim_bar(_handle_piece(1), "front")
    assert trimmed and bar[0].sum() == 0 and bar[1:, 2:38].all()
    assert int(bar.sum()) == 6 * 36  # the bar alone
    assert trim_bar(_handle_piece(3), "front")[1]  # a wide gap: three slices of posts
    assert not trim_bar(_handle_piece(0), "front")[1]  # a bar alone: nothing to trim
    assert not trim_bar(_handle_piece(1, gap=2), "front")[1]  # two runs close together
    ragged = _handle_piece(0)
    ragged = np.vstack([np.zeros((1, 40), bool), ragged])
    ragged[0, 20] = True  # one ragged cell next to the body
    assert not trim_bar(ragged, "front")[1]


def test_a_round_body_with_handles_has_no_rim_edges() -> None:
    lug = SeenMember("handle", "left", SeenBox((-0.02, 0.105, 0.02), (0.02, 0.13, 0.04)))
    assert _edges(_rimmed("cylinder", (lug,))) == ()  # a pot is held by its handles


def _cup(geom: str, mat: str) -> PerceivedObject:
    body = SeenMember("body", "", SeenBox((-0.036, -0.036, 0.0), (0.036, 0.036, 0.1)), geom)
    shape = SeenShape(0.0, np.zeros(3), body, (), SeenTop("flat", (0.072, 0.072), 0.1),
                      (0.072, 0.072), 0.0, 0.0004, 0.03, 0.0)  # fmt: skip
    return PerceivedObject(0, shape, MaterialEstimate(mat, {mat: 1.0}), 0.2, 0.1, 0.3, ())


def test_the_face_an_inverted_object_rests_on() -> None:
    """An inverted round body rests on its opening, inside its material's walls; an
    inverted box (a package) on a flat face; an upright object on a flat one."""
    glass = _cup("cylinder", "glass").as_type("t", "inverted").parts["on"]
    wall = material("glass").wall
    assert glass.shape == "open" and glass.size == pytest.approx((0.072 - 2 * wall,) * 2)
    assert _cup("box", "cardboard").as_type("b", "inverted").parts["on"].shape == "flat"
    assert _cup("cylinder", "glass").as_type("t", "upright").parts["under"].shape == "flat"


def test_a_pan_stands_on_its_base_centred_on_its_body_not_on_its_handles_box() -> None:
    """A 24 cm aluminium frying pan with a 17 cm handle: its base is the body's, centred on
    the body, and its centre of mass lies over it (the base taken at the centre of the box
    the handle widens stood 8.5 cm towards the handle: the pan tipped over in the rules)."""
    body = SeenMember("body", "", SeenBox((-0.12, -0.12, 0.0), (0.12, 0.12, 0.05)), "cylinder")
    handle = SeenMember("handle", "back", SeenBox((-0.29, -0.012, 0.03), (-0.12, 0.012, 0.045)))
    top = SeenTop("concave", (0.23, 0.23), 0.05, (0.0, 0.0), 0.005, 0.004)
    shape = SeenShape(0.0, np.zeros(3), body, (handle,), top, (0.16, 0.16), 0.3, 0.0005, 0.2, 0.0)
    pan = PerceivedObject(0, shape, MaterialEstimate("aluminium", {"aluminium": 1.0}),
                          0.6, 0.5, 0.7, ())  # fmt: skip
    t = pan.as_type("pan", "upright")
    assert t.surface_center("under") == (0.0, 0.0)
    assert t.surface_size("under") == pytest.approx((0.16, 0.16))
    assert stand_refusal(t, "under") is None


def test_a_plate_is_weighed_as_one_dish_shaped_sheet() -> None:
    plate = _rimmed("cylinder")
    assert mass_area(plate) == pytest.approx(1.2 * math.pi * 0.105**2)
    assert mass_area(plate) < 0.6 * shell_area(plate)
    tray = _rimmed("box")
    assert mass_area(tray) == shell_area(tray)  # a moulded tray keeps its shell


def test_a_board_is_weighed_solid_whatever_its_materials_typical_wall() -> None:
    """A 30 x 20 x 2 cm plastic cutting board weighs its whole volume (0.0012 m^3, 1.1 kg
    at plastic's 930 kg/m^3): weighed as a moulded shell of plastic's 2 mm walls it read
    0.26 kg, the five plastic boards of every third procedural-v1/train scene, 1.3-2.3 kg,
    read 0.24-0.37 kg."""
    board_body = SeenMember("body", "", SeenBox((-0.15, -0.1, 0.0), (0.15, 0.1, 0.02)), "box")
    board = SeenShape(0.0, np.zeros(3), board_body, (), SeenTop("flat", (0.3, 0.2), 0.02),
                      (0.3, 0.2), 0.0, 0.0004, 0.3, 0.0)  # fmt: skip
    assert bare_slab(board)
    sheet, walls = mass_areas(board)
    volume = solid_volume(board)
    assert volume == pytest.approx(0.3 * 0.2 * 0.02)
    assert estimate_mass("plastic", volume, sheet)[0] == pytest.approx(volume * 930.0)
    assert estimate_mass("plastic", volume, walls)[0] == pytest.approx(volume * 930.0)
    shell = estimate_mass("plastic", volume, shell_area(board))[0]
    assert shell < 0.3 * volume * 930.0  # what the walls rule made of it
    # a paddle board: its handle lies flat beside the slab; solid too, but not bare
    grip = SeenMember("handle", "back", SeenBox((-0.23, -0.02, 0.0), (-0.15, 0.02, 0.02)))
    paddle = replace(board, members=(grip,))
    assert slab(paddle) and not bare_slab(paddle)
    assert mass_areas(paddle) == (math.inf, math.inf)
    for rimmed in (_rimmed("box"), _rimmed("cylinder")):  # a tray and a plate keep walls
        assert not bare_slab(rimmed)
        assert mass_areas(rimmed) == (mass_area(rimmed), shell_area(rimmed))


def test_a_dishs_well_is_a_food_surface_however_narrow_a_flat_box_top_is_not() -> None:
    """A 14 cm plate's 11 cm well (or a well an object standing in it hides part of) is a
    food surface, as every well of the train catalogues is (4 of the first 40 plates have a
    well narrower than `FOOD_SURFACE`); a food box's flat top as narrow is not."""
    body = SeenMember("body", "", SeenBox((-0.07, -0.07, 0.0), (0.07, 0.07, 0.03)), "cylinder")
    well = SeenTop("flat", (0.11, 0.11), 0.01, (0.0, 0.0), 0.015, 0.015)
    plate = SeenShape(0.0, np.zeros(3), body, (), well, (0.14, 0.14), 0.0, 0.0005, 0.2, 0.0)
    mat = MaterialEstimate("ceramic", {"ceramic": 1.0})
    top = PerceivedObject(0, plate, mat, 0.3, 0.2, 0.4, ()).as_type("p", "upright").parts["on"]
    assert top.shape == "flat" and top.height is not None and top.food_surface
    box_body = SeenMember("body", "", SeenBox((-0.05, -0.03, 0.0), (0.05, 0.03, 0.15)), "box")
    box = SeenShape(0.0, np.zeros(3), box_body, (), SeenTop("flat", (0.1, 0.06), 0.15),
                    (0.1, 0.06), 0.0, 0.0005, 0.2, 0.0)  # fmt: skip
    card = MaterialEstimate("cardboard", {"cardboard": 1.0})
    lid = PerceivedObject(0, box, card, 0.3, 0.2, 0.4, ()).as_type("b", "upright").parts["on"]
    assert lid.shape == "flat" and lid.height is None and not lid.food_surface


def test_a_cavity_under_another_object_is_hidden_but_a_well_still_shows() -> None:
    """A ring seen around what stands on an inverted mug's base is not an opening; a tray's
    well around a pan standing in it is still a well."""
    grid = Grid(np.array([-0.05, -0.05]), (34, 34), 0.003)
    ij = np.indices(grid.shape).transpose(1, 2, 0)
    r = np.linalg.norm((ij + 0.5) * 0.003 - 0.05, axis=2)
    body = r <= 0.036
    over = r <= 0.028  # another object stands on it, above its top
    top = np.where(body, 0.1, -np.inf)
    top[body & (r <= 0.031)] = 0.09  # a lower ring seen between it and the rim
    top[over] = -np.inf  # no point of the body seen under it
    visible = body & ~over
    lo, hi = np.array([-0.036, -0.036]), np.array([0.036, 0.036])
    seen = classify_top(grid, top, visible, body, 0.1, "cylinder", lo, hi)
    assert seen.shape == "open"  # what the ring alone says
    hidden = classify_top(grid, top, visible, body, 0.1, "cylinder", lo, hi, over=over)
    assert not hidden.visible and hidden.shape == "flat"


@pytest.mark.parametrize(
    ("depth", "flared", "shape"),
    [
        (0.016, False, "flat"),  # a shallow well: depth 0.13 of the opening
        (0.026, False, "flat"),  # a deep plate's well: 0.21, its floor spans the opening
        (0.026, True, "open"),  # the same inside a flared outer wall: a pan, not a plate
        (0.040, False, "open"),  # 0.32: a cavity (a bowl)
    ],
)
def test_a_deep_plates_well_is_a_well_unless_its_outer_wall_flares(
    depth: float, flared: bool, shape: str
) -> None:
    cell = 0.004
    grid = Grid(np.array([-0.1, -0.1]), (50, 50), cell)
    ij = np.indices(grid.shape).transpose(1, 2, 0)
    r = np.linalg.norm((ij + 0.5) * cell - 0.1, axis=2)
    body = r <= 0.094
    top = np.where(body, 0.035, -np.inf)
    top[r <= 0.062] = 0.035 - depth  # a steep-walled well 12.4 cm across
    lo, hi = np.array([-0.094, -0.094]), np.array([0.094, 0.094])
    seen = classify_top(grid, top, body, body, 0.035, "cylinder", lo, hi, flared=flared)
    assert seen.shape == shape
    if shape == "flat":  # the well's floor, across the opening
        assert seen.height == pytest.approx(0.035 - depth)
        assert seen.size[0] == pytest.approx(0.124, abs=2 * cell)


def _round_top(cell: float = 0.004) -> tuple[Grid, np.ndarray, np.ndarray]:
    grid = Grid(np.array([-0.1, -0.1]), (50, 50), cell)
    ij = np.indices(grid.shape).transpose(1, 2, 0)
    r = np.linalg.norm((ij + 0.5) * cell - 0.1, axis=2)
    return grid, r, r <= 0.094


@pytest.mark.parametrize(
    ("rim", "flared", "shape"),
    [
        (0.032, True, "flat"),  # a plate's ledge round a shallow well, however its wall reads
        (0.004, False, "flat"),  # a thin rim round a shallow well, upright walls: a tray
        (0.004, True, "open"),  # the same inside a flared wall: a pan (`shape` makes it a dish)
    ],
)
def test_a_shallow_well_in_a_flared_thin_wall_is_no_plate(
    rim: float, flared: bool, shape: str
) -> None:
    grid, r, body = _round_top()
    top = np.where(body, 0.035, -np.inf)
    top[r <= 0.094 - rim] = 0.035 - 0.018 * (0.188 - 2 * rim) / 0.124  # depth 0.145 of it
    lo, hi = np.array([-0.094, -0.094]), np.array([0.094, 0.094])
    seen = classify_top(grid, top, body, body, 0.035, "cylinder", lo, hi, flared=flared)
    assert seen.shape == shape


def test_a_plate_whose_rim_shows_to_its_edge_in_one_place_only_is_no_dome() -> None:
    """A large plate's rim is seen up to its outer edge along a fifth of the outline only
    (elsewhere the edge's cells hold no point of the top): no ring; its inside lies lower
    than its outline all the same. A dome is highest inside."""
    grid, r, body = _round_top()
    ij = np.indices(grid.shape).transpose(1, 2, 0)
    x = (ij[..., 0] + 0.5) * 0.004 - 0.1
    lo, hi = np.array([-0.094, -0.094]), np.array([0.094, 0.094])
    visible = body & ((r <= 0.082) | (x > 0.075))
    plate = np.where(visible, np.where(r <= 0.066, 0.012, 0.03), -np.inf)
    seen = classify_top(grid, plate, visible, body, 0.03, "cylinder", lo, hi)
    assert seen.shape == "flat" and seen.height == pytest.approx(0.012)
    dome = np.where(body, 0.06 - 2.0 * r**2, -np.inf)  # 18 mm lower at its outline
    assert classify_top(grid, dome, body, body, 0.06, "cylinder", lo, hi).shape == "round"


def test_a_round_well_is_as_wide_as_its_widest_extent_where_a_glass_hides_its_edge() -> None:
    """A glass standing at the edge of a plate's well hides that side of the floor; the well
    is round, so it is as wide as it shows across the other way, centred inside the rim."""
    grid, r, body = _round_top()
    ij = np.indices(grid.shape).transpose(1, 2, 0)
    x = (ij[..., 0] + 0.5) * 0.004 - 0.1
    y = (ij[..., 1] + 0.5) * 0.004 - 0.1
    top = np.where(body, 0.03, -np.inf)
    top[r <= 0.066] = 0.012  # a well 13.2 cm across
    glass = np.hypot(x - 0.045, y) <= 0.036  # standing at the well's edge, above its top
    top[glass] = -np.inf  # no point of the plate seen under it
    visible = body & ~glass
    lo, hi = np.array([-0.094, -0.094]), np.array([0.094, 0.094])
    seen = classify_top(grid, top, visible, body, 0.03, "cylinder", lo, hi, over=glass)
    assert seen.shape == "flat"
    assert seen.size[0] == seen.size[1] == pytest.approx(0.132, abs=2 * 0.004)
    assert seen.center[0] == pytest.approx(0.0, abs=0.004)


def test_a_trays_well_under_a_board_lying_in_it_is_a_well() -> None:
    """A board lying in a tray's well, its top no higher than the tray's rim, hides most of
    the floor: too shallow for a cavity, the tray's top is still a flat well."""
    cell = 0.004
    grid = Grid(np.array([-0.2, -0.15]), (100, 75), cell)
    ij = np.indices(grid.shape).transpose(1, 2, 0)
    x, y = (ij[..., 0] + 0.5) * cell - 0.2, (ij[..., 1] + 0.5) * cell - 0.15
    body = (np.abs(x) <= 0.18) & (np.abs(y) <= 0.13)
    well = (np.abs(x) <= 0.165) & (np.abs(y) <= 0.115)
    board = (np.abs(x) <= 0.15) & (np.abs(y) <= 0.105)  # 83 % of the well
    top = np.where(body, 0.022, -np.inf)
    top[well] = 0.008
    top[board] = -np.inf  # no point of the tray seen under the board
    lo, hi = np.array([-0.18, -0.13]), np.array([0.18, 0.13])
    seen = classify_top(grid, top, body & ~board, body, 0.022, "box", lo, hi)
    assert seen.shape == "flat" and seen.height == pytest.approx(0.008)
