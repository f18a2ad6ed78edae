"""`perception.confidence`: per-attribute confidences and alternatives of a perceived object."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from utamp_gym.affordances.rim import RIM_LIFT_LIMIT
from utamp_gym.affordances.rules import EDGE_LIFT_LIMIT, LIFT_FRACTION, LOAD_CAPACITY, PAYLOAD
from utamp_gym.methods.attributes import ATTRIBUTES
from utamp_gym.methods.perceivers import _attributes
from utamp_gym.perception.confidence import (
    MASS_BOUNDS,
    SIZE_COVERAGE,
    SIZE_ERROR,
    SURFACE_COVERAGE,
    SURFACE_ERROR,
    Calibration,
    isotonic_knots,
    mass_class,
    mass_classes,
    packaged_calibration,
    raw_confidences,
    size_readings,
    surface_readings,
)
from utamp_gym.perception.material import MaterialEstimate
from utamp_gym.perception.objects import (
    SLAB_EDGE,
    SLAB_EDGE_INSET,
    THIN_TOP,
    PerceivedObject,
    _edges,
)
from utamp_gym.perception.seen import SeenBox, SeenMember, SeenShape, SeenTop
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.materials import material
from utamp_gym.suites import resolve_scene

ROOT = Path(__file__).resolve().parents[1]


def test_mass_classes_are_cut_at_the_rules_thresholds() -> None:
    rules = sorted(
        {EDGE_LIFT_LIMIT, RIM_LIFT_LIMIT, PAYLOAD * LIFT_FRACTION, LOAD_CAPACITY["sturdy"]}
    )
    assert list(MASS_BOUNDS) == rules
    assert [mass_class(m) for m in (0.2, 0.5, 0.51, 1.2, 1.6, 3.5)] == [0, 0, 1, 2, 3, 4]


def test_a_certain_material_of_a_narrow_density_gives_a_certain_mass_class() -> None:
    probs, _ = mass_classes({"plastic": 1.0}, 1e-5, 1e-3)  # a few grams
    assert probs[0] == 1.0


def test_confidences_follow_the_material_posterior() -> None:
    post = {"wood": 0.6, "cardboard": 0.3, "plastic": 0.1}
    # a solid wooden slab straddling the 1.5 kg lift limit over wood's density range
    vol = 1.5 / material("wood").density
    conf, alts = raw_confidences(post, "wood", 1.5, vol, 0.2, covered=0.25)
    assert set(conf) <= set(ATTRIBUTES)
    assert {"material", "mass", "robustness", "members"} <= set(conf)
    assert conf["material"] == 0.6
    assert alts["material"] == ("cardboard", "plastic")
    same = sum(p for m, p in post.items() if material(m).robustness == material("wood").robustness)
    assert np.isclose(conf["robustness"], same)
    assert 0.0 < conf["mass"] < 1.0
    # the wood range reaches past 1.5 kg: the heavier class is offered with its heaviest mass
    assert alts["mass"] and max(alts["mass"]) > 1.5
    assert conf["members"] == 0.75


def test_isotonic_calibration_is_monotone_and_round_trips() -> None:
    rng = np.random.default_rng(0)
    raw = rng.uniform(0, 1, 400)
    right = (rng.uniform(0, 1, 400) < raw**2).astype(float)  # over-confident raw values
    x, y = isotonic_knots(raw, right)
    assert np.all(np.diff(y) >= 0) and np.all(np.diff(x) >= 0)
    cal = Calibration.fit({"material": (raw, right)})
    assert cal("material", 0.5) < 0.45  # pulled towards 0.25 = 0.5 ** 2
    assert cal("mass", 0.7) == 0.7  # an attribute without a map keeps its raw value
    again = Calibration.from_json(cal.to_json())
    assert np.isclose(again("material", 0.5), cal("material", 0.5), atol=1e-3)


def test_the_packaged_calibration_maps_into_probabilities() -> None:
    cal = packaged_calibration()
    assert cal is not None
    for a in ("material", "mass", "robustness", "members"):
        values = [cal(a, r) for r in np.linspace(0, 1, 11)]
        assert all(0.0 <= v <= 1.0 for v in values) and np.all(np.diff(values) >= -1e-12), a


def _slab(members: tuple = (), top: str = "flat") -> SeenShape:
    body = SeenMember("body", "", SeenBox((-0.15, -0.1, 0.0), (0.15, 0.1, 0.02)))
    return SeenShape(0.0, np.zeros(3), body, members, SeenTop(top, (0.3, 0.2), 0.02),
                     (0.3, 0.2), 0.0, 0.0012, 0.13, 0.0)  # fmt: skip


def test_a_thin_top_is_a_narrow_blade_not_a_thin_board() -> None:
    """A 12 mm board 30 x 20 cm carries things (train/0064's was read thin); a blade as
    thin and 6 cm wide does not."""
    wood = MaterialEstimate("wood", {"wood": 1.0})

    def seen(width: float) -> SeenShape:
        body = SeenMember("body", "", SeenBox((-0.15, -width / 2, 0.0), (0.15, width / 2, 0.012)))
        top = SeenTop("flat", (0.3, width), 0.012)
        return SeenShape(0.0, np.zeros(3), body, (), top, (0.3, width), 0.0, 0.0012, 0.13, 0.0)

    board = PerceivedObject(1, seen(0.2), wood, 0.5, 0.5, 0.5, ()).as_type("b", "upright")
    blade = PerceivedObject(1, seen(0.06), wood, 0.1, 0.1, 0.1, ()).as_type("s", "upright")
    assert THIN_TOP > 0.012  # both are thinner than a thin top
    assert board.parts["on"].shape == "flat" and board.parts["on"].food_surface
    assert blade.parts["on"].shape == "thin"


def test_a_bare_board_is_offered_its_end_strips_as_edges() -> None:
    edges = _edges(_slab())
    assert [e.side for e in edges] == ["front", "back"]
    front = edges[0].box
    assert np.isclose(front.hi[0], 0.15) and np.isclose(front.size[0], SLAB_EDGE)
    assert np.isclose(front.size[1], 0.2 - 2 * SLAB_EDGE_INSET)
    handle = SeenMember("handle", "back", SeenBox((-0.22, -0.02, 0.0), (-0.15, 0.02, 0.02)))
    assert _edges(_slab((handle,))) == ()  # a board with a handle is held by it


def test_size_readings_narrow_and_widen_the_body_by_the_reading_error() -> None:
    t = resolve_scene("procedural-v1/train/0126").type_of("obj3")  # a tumbler
    narrow, wide = size_readings(t)
    for read, sign in ((narrow, -1), (wide, 1)):
        a, b = read.body.box, t.body.box
        np.testing.assert_allclose(np.subtract(a.max, b.max), [sign * SIZE_ERROR] * 2 + [0])
        np.testing.assert_allclose(np.subtract(a.min, b.min), [-sign * SIZE_ERROR] * 2 + [0])
        for part, attrs in t.parts.items():
            if attrs.size is not None:
                grown = np.subtract(read.parts[part].size, attrs.size)
                np.testing.assert_allclose(grown, [2 * sign * SIZE_ERROR] * 2)
        assert (read.mass, read.material, read.name) == (t.mass, t.material, t.name)
    thin = t._replace(members={"body": t.body._replace(box=Box((0, 0, 0), (0.002, 0.2, 0.1)))})
    assert size_readings(thin)[0] == thin  # no narrower reading of a 2 mm slab


def test_surface_readings_narrow_and_widen_the_top_and_bottom_surfaces_only() -> None:
    t = resolve_scene("procedural-v1/train/0056").type_of("obj1")  # a plate: a well on top
    narrow, wide = surface_readings(t)
    for read, sign in ((narrow, -1), (wide, 1)):
        assert read.members == t.members  # the body's outline stays
        for part, attrs in t.parts.items():
            if attrs.size is None:
                assert read.parts[part] == attrs
            else:
                grown = np.subtract(read.parts[part].size, attrs.size)
                np.testing.assert_allclose(grown, [2 * sign * SURFACE_ERROR] * 2)
                assert read.parts[part]._replace(size=attrs.size) == attrs
    unsized = t._replace(parts={p: a._replace(size=None) for p, a in t.parts.items()})
    assert surface_readings(unsized) == ()


def test_the_reading_errors_are_the_ones_measured_on_train() -> None:
    page = json.loads((ROOT / "docs" / "results" / "perceiver-train.json").read_text())
    measured = page["size_error"]
    assert measured["quantile"] == SIZE_COVERAGE and measured["metres"] == SIZE_ERROR
    measured = page["surface_error"]
    assert measured["quantile"] == SURFACE_COVERAGE and measured["metres"] == SURFACE_ERROR


def test_the_builtin_perceiver_offers_the_size_readings() -> None:
    glass = MaterialEstimate("glass", {"glass": 1.0})
    obj = PerceivedObject(1, _slab(), glass, 0.3, 0.3, 0.3, ())
    report = _attributes(obj, "cup", "upright")
    assert report.alternatives["member_size"] == size_readings(report.type)
    assert report.confidence_of("member_size") == SIZE_COVERAGE
    assert report.alternatives["surface"] == surface_readings(report.type) != ()
    assert report.confidence_of("surface") == SURFACE_COVERAGE
