"""Affordances: ground truth as data, the rule parser, and the noisy detector."""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.affordances.facts import load_ground_truth, restrict, score
from utamp_gym.affordances.noisy import corrupt_type, detect_affordances
from utamp_gym.affordances.rules import derive_affordances, geometric_grasps, object_facts
from utamp_gym.scene import load_catalogue
from utamp_gym.scene.catalogue import ObjectType, PartAttrs, parse_type


@pytest.fixture(scope="module")
def catalogue():
    return load_catalogue()


def test_rules_reproduce_ground_truth_exactly(catalogue) -> None:
    derived = derive_affordances(catalogue.types.values())
    truth = load_ground_truth()
    assert derived - truth == set(), f"extra: {sorted(derived - truth)}"
    assert truth - derived == set(), f"missing: {sorted(truth - derived)}"


def test_ground_truth_matches_the_paper(catalogue) -> None:
    gt = load_ground_truth()
    supported_by = lambda t: {f[4] for f in gt if f[0] == "isP2PSupportive" and f[2] == t}  # noqa: E731
    assert supported_by("salt-shaker") == set()  # supports nothing
    assert supported_by("glass-mug") == {"salt-shaker"}  # small objects only
    assert supported_by("frying-pan") == {"cutting-board"}  # only the board
    assert supported_by("wooden-tray") == {
        "salt-shaker",
        "glass-mug",
        "cutting-board",
        "frying-pan",
    }
    assert {f[1] for f in gt if f[0] == "canLift"} == {
        "salt-shaker",
        "glass-mug",
        "cutting-board",
        "frying-pan",
    }
    assert {f[1] for f in gt if f[0] == "canSlide"} == {"wooden-tray"}
    grasp_members = lambda t: {f[2] for f in gt if f[0] == "canGraspFrom" and f[1] == t}  # noqa: E731
    assert grasp_members("frying-pan") == {"handle"}  # body too large to wrap
    assert grasp_members("cutting-board") == {"handle"}
    assert grasp_members("glass-mug") == {"body", "handle"}
    assert {f[3] for f in gt if f[0] == "canGraspFrom" and f[1] == "salt-shaker"} == {
        "on"
    }  # from the top


def test_pan_body_does_not_fit_the_gripper_but_a_narrow_pan_does(catalogue) -> None:
    pan = catalogue["frying-pan"]
    assert all(m != "body" for m, *_ in geometric_grasps(pan))
    narrow_body = pan.members["body"]._replace(
        box=pan.members["body"].box._replace(min=(-0.03, -0.03, 0.0), max=(0.03, 0.03, 0.05)),
    )
    narrow = pan._replace(members={**pan.members, "body": narrow_body})
    assert any(m == "body" for m, *_ in geometric_grasps(narrow))


def test_rules_give_sensible_affordances_for_a_new_object(catalogue) -> None:
    plate = catalogue["cutting-board"]._replace(
        name="plate",
        mass=0.4,
        robustness="fragile",
        parts={**catalogue["cutting-board"].parts, "on": PartAttrs("flat", (0.20, 0.20))},
    )
    facts = derive_affordances([*catalogue.types.values(), plate])
    assert ("isSupportive", "plate", "on") in facts
    assert ("isP2PSupportive", "on", "plate", "under", "salt-shaker") in facts
    assert ("isP2PSupportive", "on", "plate", "under", "frying-pan") not in facts  # too large
    assert ("isP2PSupportive", "on", "wooden-tray", "under", "plate") in facts
    heavy = plate._replace(name="anvil", mass=20.0)
    facts = derive_affordances([catalogue["kitchen-table"], heavy])
    assert not any(f[0] == "canLift" for f in facts)
    assert ("canSlide", "anvil", "kitchen-table", "under", "on") in facts


def test_noise_is_seeded_and_scored(catalogue) -> None:
    types = list(catalogue.types.values())
    gt = load_ground_truth()
    a = detect_affordances(types, 0.1, np.random.default_rng(3), gt)
    b = detect_affordances(types, 0.1, np.random.default_rng(3), gt)
    assert a.facts == b.facts and a.scores == b.scores
    clean = detect_affordances(types, 0.0, np.random.default_rng(3), gt)
    assert clean.scores.f1 == 1.0
    f1s = [
        detect_affordances(types, 0.3, np.random.default_rng(s), gt).scores.f1 for s in range(10)
    ]
    assert np.mean(f1s) < 0.95
    with pytest.raises(ValueError):
        corrupt_type(types[0], 1.5, np.random.default_rng(0))


def test_score_and_restrict() -> None:
    ref = {("canLift", "a", "m"), ("canLift", "b", "m")}
    s = score({("canLift", "a", "m"), ("canLift", "c", "m")}, ref)
    assert (s.precision, s.recall, s.f1) == (0.5, 0.5, 0.5)
    gt = load_ground_truth()
    only = restrict(gt, ["kitchen-table", "salt-shaker"])
    assert ("isP2PSupportive", "on", "kitchen-table", "under", "salt-shaker") in only
    assert all("glass-mug" not in f for f in only)


# ------------------------------------------------------------------ rules that agree with physics
def _type(name: str, members: dict, parts: dict, mass: float = 0.3, **kw) -> ObjectType:
    sides = {s: {"shape": kw.pop("sides", "round")} for s in ("left", "right", "front", "back")}
    data = {"mass": mass, "material": kw.pop("material", "ceramic"),
            "robustness": kw.pop("robustness", "fragile"), "members": members,
            "parts": {**sides, **parts}}  # fmt: skip
    return parse_type(name, data, "<test>")


def _grasps(t: ObjectType) -> set[tuple[str, ...]]:
    return {f[2:] for f in object_facts(t) if f[0] == "canGraspFrom"}


def test_a_slab_lying_flat_leaves_no_room_beside_its_edges() -> None:
    """A handleless board's edges are declared, but a finger beside an edge would land on
    the board: no grasp. A tray's rim, with its floor below, is pinched as before."""
    edge = {"kind": "edge", "min": [0.10, -0.08, 0.0], "max": [0.12, 0.08, 0.018]}
    board = _type(
        "board",
        {"body": {"min": [-0.12, -0.1, 0.0], "max": [0.12, 0.1, 0.018]}, "edge-front": edge},
        {"on": {"shape": "flat", "food_surface": True}, "under": {"shape": "flat"}},
        sides="thin", material="wood", robustness="sturdy",
    )  # fmt: skip
    assert not _grasps(board)
    tray = load_catalogue()["wooden-tray"]
    assert ("edge-left", "on", "left", "right") in _grasps(tray)


def _bowl(wall: float, mass: float, material: str = "ceramic") -> ObjectType:
    r = 0.07
    rim = {"kind": "edge", "min": [r - wall, -0.028, 0.04], "max": [r, 0.028, 0.065]}
    return _type(
        f"bowl-{material}",
        {"body": {"geom": "cylinder", "min": [-r, -r, 0.0], "max": [r, r, 0.065]},
         "rim-front": rim},
        {"on": {"shape": "open", "size": [2 * (r - wall)] * 2}, "under": {"shape": "flat"}},
        mass=mass, material=material,
    )  # fmt: skip


def test_a_rim_is_pinched_across_a_wall_thick_enough_and_never_along_it() -> None:
    thick = _grasps(_bowl(0.008, 0.35))
    assert ("rim-front", "on", "front", "back") in thick
    # across the strip's length a finger would come down on the curved wall
    assert ("rim-front", "on", "left", "right") not in thick
    assert not _grasps(_bowl(0.0012, 0.35, "steel"))  # a steel bowl's 1.2 mm wall: not felt
    assert not _grasps(_bowl(0.005, 0.35))  # 5 mm: the squeezed pads read nothing


def test_the_open_hand_must_clear_what_it_wraps() -> None:
    def cup(d: float) -> ObjectType:
        return _type(
            f"cup-{round(d * 1000)}",
            {"body": {"geom": "cylinder", "min": [-d / 2, -d / 2, 0], "max": [d / 2, d / 2, 0.1]}},
            {"on": {"shape": "open", "size": [d - 0.006] * 2}, "under": {"shape": "flat"}},
        )

    assert _grasps(cup(0.074)) and not _grasps(cup(0.079))  # 3 mm a side in the 8 cm hand


def test_a_lid_is_grasped_only_where_the_fingers_clear_the_shoulder() -> None:
    def jar(lid_r: float, lid_h: float) -> ObjectType:
        return _type(
            f"jar-{round(lid_r * 1000)}-{round(lid_h * 1000)}",
            {"body": {"geom": "cylinder", "min": [-0.035, -0.035, 0], "max": [0.035, 0.035, 0.1]},
             "lid": {"kind": "handle", "geom": "cylinder", "min": [-lid_r, -lid_r, 0.1],
                     "max": [lid_r, lid_r, 0.1 + lid_h]}},
            {"on": {"shape": "flat", "size": [2 * lid_r] * 2, "center": [0, 0]},
             "under": {"shape": "flat"}},
            material="glass",
        )  # fmt: skip

    assert not {g for g in _grasps(jar(0.03, 0.014)) if g[0] == "lid"}  # fingers on the shoulder
    assert {g for g in _grasps(jar(0.036, 0.014)) if g[0] == "lid"}  # an overhanging lid


def test_the_weights_moment_bounds_what_a_handle_lifts() -> None:
    board = load_catalogue()["cutting-board"]
    assert ("canLift", "cutting-board", "handle") in object_facts(board)  # 0.9 N m
    heavy = board._replace(name="heavy-board", mass=1.2)  # 1.8 N m at 15.5 cm
    assert not any(f[0] == "canLift" for f in object_facts(heavy))


def test_an_object_stands_only_over_its_centre_of_mass() -> None:
    pan = load_catalogue()["frying-pan"]
    assert ("isSupportable", "frying-pan", "under") in object_facts(pan)
    handle = pan.members["handle"]
    long = handle._replace(box=handle.box._replace(min=(-0.5, -0.03, 0.02)))  # a heavy handle
    tipping = pan._replace(name="tipping-pan", members={**pan.members, "handle": long})
    assert ("isSupportable", "tipping-pan", "under") not in object_facts(tipping)


def test_what_is_taller_than_wide_keeps_off_the_edge_of_a_small_foot() -> None:
    def glass(d: float, name: str) -> ObjectType:
        return _type(
            name,
            {"body": {"geom": "cylinder", "min": [-d / 2, -d / 2, 0], "max": [d / 2, d / 2, 0.12]}},
            {"on": {"shape": "open", "size": [d - 0.006] * 2}, "under": {"shape": "flat"}},
            material="glass", mass=0.2,
        )  # fmt: skip

    lower, same, narrower = glass(0.07, "lower"), glass(0.07, "same"), glass(0.06, "narrower")
    facts = derive_affordances([lower, same, narrower])
    # upside down, the lower glass's foot faces up (`under`); the upper one stands on its rim
    assert ("isP2PSupportive", "under", "lower", "on", "narrower") in facts
    assert ("isP2PSupportive", "under", "lower", "on", "same") not in facts
