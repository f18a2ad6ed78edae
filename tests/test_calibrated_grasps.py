"""The extended domain's grasps calibrated on forbidden picks physics made
(`utamp_gym.affordances.calibrated`, thick rim pinches in `utamp_gym.affordances.rim`):
each rule's decision from geometry, and that decision checked against physics on the
procedural-v1 instance it was measured on (a grant lifts and places, a refusal fails)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from utamp_gym.affordances.calibrated import EXTENDED_LIFT_LIMIT, LOW_COVER_LIMIT
from utamp_gym.affordances.rim import THICK_TORQUE_LIMIT, rim_pinch_refusal
from utamp_gym.affordances.rules import object_facts, pick_refusal
from utamp_gym.kitchenware import generate

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_scripts"))
import readme

grasp_coverage = readme.load_script("benchmarks/grasp_coverage.py")

physics = pytest.mark.physics


def _grants(fam: str, seed: int, member: str, f1: str, f2: str, extended: bool) -> bool:
    t = generate(fam, "v1", seed)
    facts = object_facts(t, extended)
    grasp = ("canGraspFrom", t.name, member, "on", f1, f2)
    return grasp in facts and ("canLift", t.name, member) in facts


def test_a_lug_is_pinched_with_the_wall_behind_it_in_the_extended_domain_only():
    t = generate("stock-pot", "v1", 1)  # 1.76 kg: over the paper's payload too
    assert pick_refusal(t, "handle-left", "on", "left", "right").rule == "finger-blocked"
    assert t.mass > 1.5 and t.mass <= EXTENDED_LIFT_LIMIT
    assert not _grants("stock-pot", 1, "handle-left", "left", "right", False)
    assert _grants("stock-pot", 1, "handle-left", "left", "right", True)
    # too heavy even for the extended payload: refused
    heavy = generate("stock-pot", "v1", 17)
    assert heavy.mass > EXTENDED_LIFT_LIMIT
    assert not _grants("stock-pot", 17, "handle-left", "left", "right", True)


def test_a_body_under_a_low_lid_is_grasped_and_under_a_tall_one_not():
    low, tall = generate("jar", "v1", 8), generate("jar", "v1", 1)
    assert low.members["lid"].box.size[2] <= LOW_COVER_LIMIT < tall.members["lid"].box.size[2]
    assert pick_refusal(low, "body", "on", "left", "right").rule == "covered"
    assert not _grants("jar", 8, "body", "left", "right", False)
    assert _grants("jar", 8, "body", "left", "right", True)
    assert not _grants("jar", 1, "body", "left", "right", True)


def test_a_thick_rim_carries_up_to_the_thick_torque_limit():
    held = rim_pinch_refusal(generate("tray", "v1", 2), "edge-left", "on", "left", "right")
    assert held is None  # 1.57 kg at 2.27 N m
    slips = rim_pinch_refusal(generate("tray", "v1", 6), "edge-left", "on", "left", "right")
    assert slips is not None and slips.rule == "torque"
    assert slips.values["moment"] > THICK_TORQUE_LIMIT


def test_the_extended_rules_only_add_to_the_paper_rules_on_the_calibrated_families():
    for fam in ("stock-pot", "jar", "tray", "saucepan", "paddle-board", "frying-pan"):
        for seed in range(12):
            t = generate(fam, "v1", seed)
            assert object_facts(t) <= object_facts(t, True), (fam, seed)


def test_procedural_v2_draws_its_goals_with_the_rules_before_the_calibration():
    pot, tray = generate("stock-pot", "v1", 1), generate("tray", "v1", 2)
    lug = ("canGraspFrom", pot.name, "handle-left", "on", "left", "right")
    rim = ("canLift", tray.name, "edge-left")
    assert lug in object_facts(pot, True) and lug not in object_facts(pot, True, False)
    assert rim in object_facts(tray, True) and rim not in object_facts(tray, True, False)


# ------------------------------------------------------------------ physics
def _lone(fam: str, seed: int) -> Any:
    """The benchmark's scene: instance `seed` of `fam` alone on a two-slot table."""
    return grasp_coverage.lone_scene(fam, seed)


@pytest.fixture(scope="module")
def sim():
    from utamp_gym.sim.backend import MujocoBackend

    backend = MujocoBackend(pose_noise=0.0)
    yield backend
    backend.close()


def _pick_and_place(sim: Any, fam: str, seed: int, grasp: str) -> str:
    sim.reset(_lone(fam, seed), np.random.default_rng(seed))
    picked = sim.execute(f"(pick-support obj obj-{grasp} under on slot1 under on)")
    if not picked.success:
        return picked.reason or "pick failed"
    placed = sim.execute(f"(place-support obj obj-{grasp} under on under slot2 under on)")
    return "" if placed.success else placed.reason or "place failed"


@physics
@pytest.mark.parametrize(
    ("fam", "seed", "member", "f1", "f2"),
    [
        ("stock-pot", 1, "handle-left", "left", "right"),  # granted: lug and wall
        ("jar", 8, "body", "left", "right"),  # granted: around a 15 mm lid
        ("jar", 1, "body", "left", "right"),  # refused: a 24 mm lid stops the hand
        ("tray", 2, "edge-left", "left", "right"),  # granted: 2.27 N m
        ("tray", 6, "edge-left", "left", "right"),  # refused: 2.70 N m slips
        ("sheet-pan", 20, "edge-left", "left", "right"),  # refused: a 19.9 mm rim, 2.1 N m
        ("bowl", 0, "rim-front", "front", "back"),  # granted: a light steel bowl, at 15 N
        ("tumbler", 0, "body", "front", "back"),  # granted: a light steel tumbler, at 15 N
    ],
)
def test_the_rule_decides_as_physics_does(sim, fam, seed, member, f1, f2):
    granted = _grants(fam, seed, member, f1, f2, True)
    why = _pick_and_place(sim, fam, seed, f"{member} on {f1} {f2}")
    assert (why == "") == granted, (granted, why)
