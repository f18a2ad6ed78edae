"""The rules' refusals: each names the test that fails, its numbers do fail it, and asking
with why=True (an explanation) and why=False (a decision) gives the same answer."""

from __future__ import annotations

import math

import pytest

from utamp_gym.affordances import hand, rules
from utamp_gym.affordances.why import TEMPLATES, Refusal
from utamp_gym.kitchenware import FAMILIES, generate
from utamp_gym.scene.catalogue import ObjectType, load_catalogue
from utamp_gym.scene.geometry import SIDES
from utamp_gym.suites.generate import extra_catalogue


@pytest.fixture(scope="module")
def types() -> list[ObjectType]:
    out = [*load_catalogue().types.values(), *extra_catalogue().types.values()]
    for family in FAMILIES:
        out += [generate(family, "v1", i, validate=False) for i in range(6)]
    pan = load_catalogue()["frying-pan"]
    handle = pan.members["handle"]
    long = handle._replace(box=handle.box._replace(min=(-0.5, -0.03, 0.02)))  # a heavy handle
    return [*out, pan._replace(name="tipping-pan", members={**pan.members, "handle": long})]


def _violates(r: Refusal) -> bool:
    """The refusal's own numbers break its rule's limit (or it names no numbers)."""
    v = r.values
    checks = {
        "load-capacity": lambda: v["mass"] > v["capacity"],
        "payload": lambda: v["mass"] > v["limit"],
        "torque": lambda: (
            v["moment"] > v["limit"] and math.isclose(v["moment"], v["mass"] * hand.G * v["lever"])
        ),
        "grip-width": lambda: v["width"] > v["limit"],
        "too-thin": lambda: v["width"] < v["limit"],
        "pinch": lambda: v["width"] < v["limit"],
        "footprint": lambda: any(
            f + v["margin"] > s + 1e-9 for f, s in zip(v["footprint"], v["surface"], strict=True)
        ),
        "footprint-disc": lambda: v["size"] + v["margin"] > v["disc"] + 1e-9,
        "span": lambda: any(
            f < s + 2 * v["margin"] - 1e-9 for f, s in zip(v["standing"], v["opening"], strict=True)
        ),
        "tips-over": lambda: any(
            o > h - v["margin"] for o, h in zip(v["offset"], v["half"], strict=True)
        ),
        "finger-room": lambda: v["shortfall"] > hand.TOUCH and v["other"] is not None,
    }
    return checks.get(r.rule, lambda: True)()


def test_every_refusal_is_its_decision_and_its_numbers_fail_the_rule(types) -> None:
    seen: set[str] = set()
    pick = [t for t in types if t.movable]
    for t in types:
        for part in SIDES:
            for refusal, decision in (
                (rules.supportive_refusal(t, part), rules.is_supportive(t, part)),
                (rules.supportable_refusal(t, part), rules.is_supportable(t, part)),
            ):
                assert (refusal is None) == decision
                if refusal is not None:
                    seen.add(refusal.rule)
                    assert _violates(refusal), refusal.detail
        grasps = set(rules.geometric_grasps(t))
        for member in t.members:
            for palm in rules.PALM_PARTS:
                for f1, f2 in rules.FINGER_PAIRS:
                    refusal = rules.grasp_refusal(t, member, palm, f1, f2)
                    assert (refusal is None) == ((member, palm, f1, f2) in grasps)
                    picked = rules.pick_refusal(t, member, palm, f1, f2)
                    for r in (refusal, picked):
                        if r is not None:
                            seen.add(r.rule)
                            assert _violates(r), r.detail
                            assert r.detail and r.rule in TEMPLATES
    for t2 in types[:40]:
        for t1 in pick[::3]:
            for p2 in ("on", "under"):
                for p1 in ("on", "under"):
                    refusal = rules.p2p_refusal(t2, p2, t1, p1)
                    assert (refusal is None) == rules.p2p_supportive(t2, p2, t1, p1)
                    if refusal is not None:
                        seen.add(refusal.rule)
                        assert _violates(refusal), refusal.detail
    # the sample reaches the rules that carry numbers
    assert {"load-capacity", "payload", "torque", "grip-width", "footprint", "span"} <= seen
    assert {"finger-room", "tips-over", "never-up", "surface-shape"} <= seen


def test_refusal_text_and_json_carry_the_numbers() -> None:
    cat = load_catalogue()
    board, tray = cat["cutting-board"], cat["wooden-tray"]
    heavy = board._replace(name="heavy-board", mass=2.0)
    lift = rules.pick_refusal(heavy, "handle", "on", "left", "right")
    assert lift is not None and lift.rule == "payload"
    assert lift.detail.startswith("mass 2.00 kg > 1.50 kg")
    assert lift.to_json()["values"] == {
        "member": "handle",
        "mass": 2.0,
        "limit": 1.5,
        "kind": "wrapping",
        "payload": 3.0,
    }
    held = rules.pick_refusal(board._replace(mass=1.2), "handle", "on", "left", "right")
    assert held is not None and held.rule == "torque"  # light enough, but it turns
    assert held.detail.endswith("1.82 N m (1.20 kg at 15.5 cm) > 1.4 N m")
    blocked = rules.pick_refusal(board, "handle", "on", "front", "back")
    assert blocked is not None and blocked.rule == "finger-blocked"
    assert blocked.detail == "body lies within 0.5 cm of handle's front side"
    wide = rules.p2p_refusal(board, "on", tray, "under")  # the tray is larger than the board
    assert wide is not None and wide.rule == "load-capacity"  # 3.5 kg > a board's 3 kg
    assert wide.detail == "mass 3.50 kg > 3.0 kg, the load a sturdy cutting-board carries"
    nested = rules.supportive_refusal(tray, "under")
    assert nested is not None and nested.rule == "never-up"
    assert nested.to_json()["values"]["why"]["rule"] == "food-surface"
