"""`utamp plan --explain` on procedural-v2: its default method (utamp2x-rules, the extended
domain) names the goal literals the rules block, with the rules' numbers."""

from __future__ import annotations

import json
from typing import Any

from utamp_gym.affordances import rules
from utamp_gym.affordances.rim import rim_pinch_refusal
from utamp_gym.affordances.sources import affordances_for, scene_types
from utamp_gym.cli import main
from utamp_gym.eval.explain import NO_CORRECTION, explain_unsolvable
from utamp_gym.suites import resolve_scene
from utamp_gym.suites.procedural_v2 import split_scenes

BOARD = "procedural-v2/test-tasks/0009"  # "put all the boards on the bottle": the base board
TRAY = "procedural-v2/test-families/0002"  # "set the saucepan down on the tray"
BOWLS = "procedural-v2/test-count/0002"  # a tower over upside-down bowls and a bowl upright


def _explain(capsys, scene: str, *more: str) -> tuple[str, dict[str, Any]]:
    """`utamp plan SCENE --explain` (its default method): the text and the JSON output."""
    assert main(["plan", scene, "--explain", *more]) == 0
    text = capsys.readouterr().out
    assert main(["plan", scene, "--explain", "--json", *more]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] is False
    for block in data["explanation"]["blocking"]:  # each block is printed with its rule
        assert f"      {block['subject']}: {block['detail']} [{block['rule']}]" in text
    return text, data


def test_a_v2_board_nothing_lifts_is_named_with_the_grasp_and_rim_rules(capsys) -> None:
    text, data = _explain(capsys, BOARD)
    assert data["method"] == "utamp2x-rules"  # the labelling method, by default
    expl = data["explanation"]
    assert "explanations need" not in text
    atom = "(not (oc under base slot1))"
    assert expl["headline"].startswith(f"{NO_CORRECTION}: even the ground truth cannot reach")
    assert {b["atom"] for b in expl["blocking"]} == {atom} and expl["rest_solvable"] is True
    picks = [b for b in expl["blocking"] if b["stage"] == "pick"]
    assert {b["object"] for b in picks} == {"base"}
    by_rule = {(b["rule"], b["values"]["member"]): b["values"] for b in picks}
    body = by_rule["grip-width", "body"]
    assert body["limit"] == 0.074 and body["width"] > 0.2  # wrapped: 7.4 cm of the 8 cm
    assert by_rule["grip-width", "edge-front"]["limit"] == 0.08  # an edge is pinched
    room = by_rule["finger-room", "edge-front"]
    assert room["shortfall"] > room["tolerance"] == 0.002
    # the extended domain's rim pinch is asked too, with its own tolerance
    pinch = by_rule["rim-finger-room", "edge-front"]
    assert pinch["shortfall"] > pinch["tolerance"] == 0.005
    assert "cannot be pinched at the rim by edge-front (front/back): pinching edge-front" in text
    # the grasps come first, then the pinches
    assert text.index("cannot be picked up by") < text.index("cannot be pinched at the rim")
    places = {b["rule"]: b["values"] for b in expl["blocking"] if b["stage"] == "place"}
    assert places["load-capacity"]["capacity"] == 0.5 and places["load-capacity"]["mass"] > 1
    assert "the load a fragile bottle" in text


def test_a_v2_saucepan_the_tray_refuses_is_named_with_its_footprint(capsys) -> None:
    text, data = _explain(capsys, TRAY)
    (block,) = data["explanation"]["blocking"]
    assert block["atom"] == "(oc under obj1 base)" and block["rule"] == "footprint"
    assert block["stage"] == "place" and block["object"] == "obj1"
    values = block["values"]
    assert values["footprint"][0] > values["surface"][0]  # 36.6 cm on a 35.3 cm floor
    assert values["margin"] == 0.008 and values["margin_why"] == "to clear its rim"
    assert "(+0.8 cm to clear its rim) exceeds tray-v1-" in text


def test_the_extended_rules_explain_what_the_papers_rules_would_not(capsys) -> None:
    """The upright bowl that only a rim pinch lifts blocks the paper's domain, not utamp2x."""
    _, ext = _explain(capsys, BOWLS)
    _, paper = _explain(capsys, BOWLS, "--method", "utamp2-gt")
    blocked = {b["object"] for b in ext["explanation"]["blocking"]}
    assert blocked == {"obj2", "obj3"}  # the two upside-down bowls
    assert "obj5" in {b["object"] for b in paper["explanation"]["blocking"]}
    assert not any("pinched at the rim" in b["subject"] for b in paper["explanation"]["blocking"])


def test_every_v2_block_comes_from_a_rule_not_a_missing_fact() -> None:
    """The refusals asked of the extended rules agree with the facts they derive: no
    unachievable scene of a test split is blocked by a fact the rules would grant."""
    explained = 0
    for split in ("test-instances", "test-families", "test-count", "test-tasks"):
        for s in (s for s in split_scenes(split) if not s.achievable):
            facts, _ = affordances_for(s.scene, "rules", None, domain="utamp2x")
            e = explain_unsolvable(s.scene, facts, domain="utamp2x")
            assert not e.found, s.scene.name
            assert "ground-truth" not in {b.refusal.rule for b in e.blocking}, s.scene.name
            assert set(e.blocked_atoms) <= set(s.scene.goal.literals)
            explained += bool(e.blocking)
            if "goal-order" in {b.refusal.rule for b in e.blocking}:  # only when no move's
                assert {b.stage for b in e.blocking} == {"order"}
                assert all(b.refusal.values["why"] for b in e.blocking)
    assert explained == 40  # every unachievable goal of the four test splits


def test_extended_pick_refusals_decide_as_the_extended_facts() -> None:
    """A grasp whose extended refusal and rim-pinch refusal both refuse it is never granted
    with a lift of that member by the same palm; one they allow is granted."""
    types = {t.name: t for s in split_scenes("test-count")[:30] for t in scene_types(s.scene)}
    checked = 0
    for t in types.values():
        facts = rules.object_facts(t, True)
        for m, member in t.members.items():
            for palm in rules.PALM_PARTS:
                for f1, f2 in rules.FINGER_PAIRS:
                    allowed = rules.pick_refusal(t, m, palm, f1, f2, True) is None
                    if palm == "on" and member.kind in ("edge", "body"):
                        allowed |= rim_pinch_refusal(t, m, palm, f1, f2) is None
                    grasp = ("canGraspFrom", t.name, m, palm, f1, f2) in facts
                    if allowed:
                        assert grasp and ("canLift", t.name, m) in facts, (t.name, m, palm, f1)
                    elif grasp:  # granted as a grasp only when another palm lifts the member
                        others = [p for p in rules.PALM_PARTS if p != palm]
                        assert ("canLift", t.name, m) not in facts or any(
                            rules.pick_refusal(t, m, p, a, b, True) is None
                            for p in others
                            for a, b in rules.FINGER_PAIRS
                        ), (t.name, m, palm, f1)
                    checked += 1
    assert checked > 1000


def test_a_v2_scene_resolves_with_its_goal() -> None:
    assert resolve_scene(BOARD).goal is not None


def test_a_goal_no_order_of_moves_reaches_names_its_literal(capsys) -> None:
    """The food box must go onto the tray, under the bottle, and every table region is taken:
    each move is possible, no order of them reaches the literal."""
    text, data = _explain(capsys, "procedural-v2/test-count/0019")
    (block,) = data["explanation"]["blocking"]
    assert block["atom"] == "(oc under obj4 base)" and block["stage"] == "order"
    assert block["rule"] == "goal-order" and block["values"]["why"] == "not even alone"
    assert "no order of moves reaches (oc under obj4 base): not even alone [goal-order]" in text
