"""Affordances: ground truth as data, the rule parser, and the noisy detector."""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.affordances.facts import load_ground_truth, restrict, score
from utamp_gym.affordances.noisy import corrupt_type, detect_affordances
from utamp_gym.affordances.rules import derive_affordances, geometric_grasps
from utamp_gym.scene import load_catalogue
from utamp_gym.scene.catalogue import PartAttrs


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
