"""Why-not explanations: the smallest set of affordance corrections that unblocks a scene."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import tomli_w

from utamp_gym.affordances.sources import ground_truth_for
from utamp_gym.cli import main
from utamp_gym.eval.explain import NO_CORRECTION, explain_unsolvable, format_fact
from utamp_gym.eval.runner import EvalTask, run_task
from utamp_gym.eval.solvability import SolvabilityOracle
from utamp_gym.planning.methods import plan_scene
from utamp_gym.suites import get_scene, resolve_scene, suite_scenes

PAN_SUPPORTS_BOARD = ("isP2PSupportive", "on", "frying-pan", "under", "cutting-board")
SCENE = "pick-place/013"  # tray/pan | board: the board must go onto the pan


def _unsolved_noisy_seed(scene: str, noise: float = 0.3) -> int:
    for seed in range(100):
        if not plan_scene(get_scene(scene), "utamp2-noisy", seed=seed, noise=noise).solved:
            return seed
    raise AssertionError("no unsolvable noisy detection in 100 seeds")


def test_removed_pan_supports_board_is_named() -> None:
    scene = get_scene(SCENE)
    assert {o.type for o in scene.objects} >= {"frying-pan", "cutting-board"}
    detected = ground_truth_for(scene) - {PAN_SUPPORTS_BOARD}
    expl = explain_unsolvable(scene, detected)
    assert expl.found and expl.smallest
    assert expl.missing == (PAN_SUPPORTS_BOARD,) and expl.spurious == ()
    assert "isP2PSupportive(on, frying-pan, under, cutting-board)" in expl.message


def test_two_missing_facts_are_both_required() -> None:
    scene = get_scene(SCENE)
    gone = {PAN_SUPPORTS_BOARD, ("canLift", "cutting-board", "handle")}
    expl = explain_unsolvable(scene, ground_truth_for(scene) - gone)
    assert set(expl.missing) == gone and expl.smallest


def test_spurious_can_lift_blocks_sliding() -> None:
    scene = suite_scenes("sliding")[0]
    members = ("handle-front", "handle-back", "edge-left", "edge-right")
    spurious = {("canLift", "wooden-tray", m) for m in members}
    expl = explain_unsolvable(scene, ground_truth_for(scene) | spurious)
    assert expl.found and not expl.missing
    assert expl.spurious and set(expl.spurious) <= spurious


def test_oracle_agrees_with_the_planner() -> None:
    scene = get_scene(SCENE)
    gt = ground_truth_for(scene)
    oracle = SolvabilityOracle(scene, gt)
    assert oracle(gt)
    assert not oracle(gt - {PAN_SUPPORTS_BOARD})
    text = "isP2PSupportive(on, frying-pan, under, cutting-board)"
    assert format_fact(PAN_SUPPORTS_BOARD) == text


def test_failure_reason_in_results_names_the_missing_facts() -> None:
    seed = _unsolved_noisy_seed(SCENE)
    task = EvalTask(SCENE, "utamp2-noisy", seed=seed, grounding="symbolic", noise=0.3)
    row = run_task(task)
    assert not row.solved and not row.crashed
    assert row.failure_reason.startswith("not solved: ")
    assert "missing affordance facts: " in row.failure_reason or "spurious" in row.failure_reason


def test_plan_explain_cli(capsys) -> None:
    seed = _unsolved_noisy_seed(SCENE)
    args = ["plan", SCENE, "--method", "utamp2-noisy", "--noise", "0.3", "--seed", str(seed)]
    assert main([*args, "--explain"]) == 0
    out = capsys.readouterr().out
    assert "not solved" in out and "why not: " in out
    assert main([*args, "--explain", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] is False and data["explanation"]["found"]
    assert data["explanation"]["missing"] or data["explanation"]["spurious"]
    assert main(["plan", SCENE, "--explain", "--json"]) == 0  # solved: nothing to explain
    assert json.loads(capsys.readouterr().out)["explanation"] is None


# ------------------------------------------- goals the ground truth itself cannot reach
SCENES = Path(__file__).parent / "scenes"
SLOT2 = "(oc on slot2 air)"  # where the blocking object stands in each scene file


def _explain_file(capsys, name: str) -> tuple[str, dict[str, Any]]:
    """`utamp plan FILE --explain`: the text output and the JSON explanation."""
    path = str(SCENES / f"{name}.toml")
    assert main(["plan", path, "--explain"]) == 0
    text = capsys.readouterr().out
    assert main(["plan", path, "--explain", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] is False
    expl = data["explanation"]
    assert not expl["found"] and expl["message"].startswith(NO_CORRECTION)
    assert f"why not: {NO_CORRECTION}: even the ground truth cannot reach {SLOT2} " in text
    assert {b["atom"] for b in expl["blocking"]} == {SLOT2}  # the salt shaker's slot is free
    assert expl["rest_solvable"] is True
    lines = text.splitlines()
    assert f"    {SLOT2}:" in lines
    for block in expl["blocking"]:
        assert f"      {block['subject']}: {block['detail']} [{block['rule']}]" in lines
        assert block["text"].startswith(f"{SLOT2}: {block['subject']}: {block['detail']}")
    return text, expl


def _rules(expl: dict[str, Any], stage: str) -> dict[str, list[dict[str, Any]]]:
    out: dict[str, list[dict[str, Any]]] = {}
    for b in expl["blocking"]:
        if b["stage"] == stage:
            out.setdefault(b["rule"], []).append(b)
    return out


def test_explain_names_the_payload_that_a_heavy_pot_exceeds(capsys) -> None:
    text, expl = _explain_file(capsys, "heavy-pot")
    assert "pot (heavy-pot) cannot be picked up by handle-left (front/back), handle-right" in text
    assert "mass 4.00 kg > 1.50 kg, what a wrapping grasp lifts" in text
    payload = _rules(expl, "pick")["payload"]
    assert len(payload) == 1 and payload[0]["values"]["mass"] == 4.0
    assert payload[0]["values"]["limit"] == 1.5 and payload[0]["values"]["payload"] == 3.0
    tray = [b for b in _rules(expl, "place")["load-capacity"] if b["subject"].startswith("tray")]
    assert tray[0]["values"] | {"mass": 4.0, "capacity": 3.0} == tray[0]["values"]
    assert "mass 4.00 kg > 3.0 kg, the load a sturdy wooden-tray carries" in expl["message"]


def test_explain_names_the_footprint_the_tray_refuses(capsys) -> None:
    text, expl = _explain_file(capsys, "oversized-colander")
    assert not _rules(expl, "pick")  # light, with handles: only its place is refused
    (tray,) = _rules(expl, "place")["footprint"]
    assert tray["subject"] == "tray (wooden-tray) does not carry colander (colander)"
    values = tray["values"]
    assert values["footprint"] == [0.24, 0.29] and values["surface"] == [0.32, 0.29]
    assert values["margin"] == 0.008 and values["supporter"] == "wooden-tray"
    detail = "colander's footprint 24.0 x 29.0 cm (+0.8 cm to clear its rim) exceeds "
    assert detail + "wooden-tray's on surface 32.0 x 29.0 cm [footprint]" in text


def test_explain_names_the_grasps_a_handleless_board_leaves_no_room_for(capsys) -> None:
    text, expl = _explain_file(capsys, "handleless-board")
    assert not _rules(expl, "place")  # the tray would carry it: it cannot be picked up
    pick = _rules(expl, "pick")
    widths = {(b["values"]["member"], b["values"]["fingers"]): b for b in pick["grip-width"]}
    body = widths["body", "front/back"]["values"]
    assert body["width"] == 0.24 and body["limit"] == 0.074 and body["opening"] == 0.08
    assert widths["edge-front", "left/right"]["values"]["limit"] == 0.08  # an edge is pinched
    rooms = {b["values"]["member"]: b["values"] for b in pick["finger-room"]}
    assert set(rooms) == {"edge-front", "edge-back"}
    assert rooms["edge-front"]["side"] == "back" and rooms["edge-front"]["other"] == "body"
    assert rooms["edge-front"]["shortfall"] > rooms["edge-front"]["tolerance"] == 0.002
    assert "the back finger would stop 1.5 cm above its target, on its body" in text
    assert text.index("[finger-room]") < text.index("[grip-width]")  # the closest test first


def test_a_fact_the_hand_written_truth_lacks_is_named_as_such() -> None:
    scene = resolve_scene("kitchen-demo")
    salt = ("canLift", "salt-shaker", "body")
    gt = ground_truth_for(scene) - {salt}
    expl = explain_unsolvable(scene, gt, ground_truth=gt)
    assert not expl.found and expl.blocked_atoms == ("(oc on slot5 air)",)
    (block,) = expl.blocking
    assert block.object == "salt" and block.refusal.rule == "ground-truth"
    assert block.refusal.detail == (
        "canLift(salt-shaker, body) is not in the hand-written ground truth (the rules grant it)"
    )


def test_objects_that_each_fit_but_not_together_are_named(tmp_path) -> None:
    data = tomllib.loads((SCENES / "heavy-pot.toml").read_text())
    data["objects"][1] = {"name": "salt2", "type": "salt-shaker", "on": "slot2"}
    del data["types"]
    path = tmp_path / "two-shakers.toml"
    path.write_text(tomli_w.dumps(data))
    scene = resolve_scene(str(path))
    expl = explain_unsolvable(scene, ground_truth_for(scene))
    # each shaker can stand on the tray, but not both, and neither carries the other
    assert expl.blocked_atoms == ("(oc on slot2 air)", "(oc on slot3 air)")
    assert [(b.object, b.refusal.rule) for b in expl.blocking] == [
        ("salt2", "one-tower"),
        ("salt", "one-tower"),
    ]
    detail = "every object can join the tower on its own, but not all together: "
    assert expl.blocking[0].refusal.detail == detail + "without salt2, the others stack"


def test_a_found_explanation_has_no_blocks() -> None:
    scene = get_scene(SCENE)
    expl = explain_unsolvable(scene, ground_truth_for(scene) - {PAN_SUPPORTS_BOARD})
    assert expl.found and expl.blocking == () and expl.rest_solvable is None
    assert expl.to_json()["blocking"] == [] and expl.headline == expl.message


def test_failure_reason_in_results_names_the_blocking_rule() -> None:
    task = EvalTask(str(SCENES / "heavy-pot.toml"), "utamp2-gt", seed=0, grounding="symbolic")
    row = run_task(task)
    assert not row.solved and not row.crashed
    reason = row.failure_reason
    assert f"{NO_CORRECTION}: even the ground truth cannot reach {SLOT2}" in reason
    assert "mass 4.00 kg > 1.50 kg, what a wrapping grasp lifts" in reason
    assert reason.count("[payload]") == 1 and reason.count("[grip-width]") == 0  # one a stage


def test_an_object_that_cannot_stand_on_its_face_is_named(tmp_path) -> None:
    data = tomllib.loads((SCENES / "heavy-pot.toml").read_text())
    data["objects"][1] = {
        "name": "board",
        "type": "cutting-board",
        "on": "slot2",
        "orientation": "inverted",
    }
    del data["types"]
    path = tmp_path / "face-down-board.toml"
    path.write_text(tomli_w.dumps(data))
    scene = resolve_scene(str(path))
    expl = explain_unsolvable(scene, ground_truth_for(scene))
    assert expl.blocked_atoms == (SLOT2,)
    stages = {b.stage: b for b in expl.blocking}
    assert set(stages) == {"pick", "stand"}  # no place reasons once it cannot stand
    stand = stages["stand"]
    assert stand.subject == "board (cutting-board, upside down) cannot be put down on its on"
    assert stand.refusal.rule == "food-surface"
