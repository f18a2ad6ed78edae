"""Rim pinches of the extended domain (utamp2x): the rules' decision from geometry, the
decoder's pinch point, and the decision checked against physics (bowls at their parameter
extremes at several yaws, plates by their rim, a frying pan the rules refuse).

The physics tests look only at what the simulation measured (the skills' own checks: the
object rose with the hand, held in the pads, and stands on the other slot afterwards)."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from utamp_gym.affordances.hand import GRIPPER_OPENING, WRAP_CLEARANCE
from utamp_gym.affordances.rim import rim_pinch_refusal
from utamp_gym.affordances.rules import object_facts, pick_refusal
from utamp_gym.kitchenware import extreme_type, family, generate, type_table
from utamp_gym.kitchenware.params import extremes
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.scene.shapes import WRAP_LIMIT, rim_strip
from utamp_gym.sim.decode import GraspSymbols, grasp_candidates
from utamp_gym.symbolic.problem import DOMAINS, domain_text

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_scripts"))
import readme

grasp_coverage = readme.load_script("benchmarks/grasp_coverage.py")
physics = pytest.mark.physics
YAWS = (0.0, 0.8, 2.0, -2.6)


def _lifts(t: Any, extended: bool) -> bool:
    return any(f[0] == "canLift" for f in object_facts(t, extended))


# ------------------------------------------------------------------ rules and decoding
def test_the_wrap_limit_is_the_hands():
    assert pytest.approx(GRIPPER_OPENING - 2 * WRAP_CLEARANCE) == WRAP_LIMIT


def test_a_thin_steel_bowl_is_refused_by_the_paper_rules_and_pinched_in_the_extended():
    bowl = extreme_type("bowl", "steel", False)  # a 1.1 mm rolled rim
    assert pick_refusal(bowl, "rim-front", "on", "front", "back").rule == "too-thin"
    assert not _lifts(bowl, False)
    assert rim_pinch_refusal(bowl, "rim-front", "on", "front", "back") is None
    assert ("canLift", bowl.name, "rim-front") in object_facts(bowl, True)
    # across the rim the fingers would not straddle the wall; from below never
    assert rim_pinch_refusal(bowl, "rim-front", "on", "left", "right").rule == "rim-across"
    assert rim_pinch_refusal(bowl, "rim-front", "under", "front", "back").rule == "rim"


def test_the_extended_rules_only_add_to_the_paper_rules():
    for fam in ("bowl", "plate", "tumbler", "saucepan", "tray", "mug"):
        for seed in range(10):
            t = generate(fam, "v1", seed)
            assert object_facts(t) <= object_facts(t, True)


def test_a_wide_tumbler_is_pinched_at_its_wall_where_the_decoder_puts_the_fingers():
    t = next(
        generate("tumbler", "v1", s)
        for s in range(40)
        if not _lifts(generate("tumbler", "v1", s), False)
    )
    r = t.body.box.max[0]
    wall = (2 * r - t.parts["on"].size[0]) / 2
    strip = rim_strip(t, "body", "on", "front")
    assert strip.min[0] == pytest.approx(r - wall) and strip.max[0] == pytest.approx(r)
    assert rim_strip(t, "body", "under", "front") is None
    g = grasp_candidates(t, GraspSymbols("o", "body", "on", "front", "back"), np.eye(4),
                         prefer_x=np.array([1.0, 0.0, 0.0]))[0]  # fmt: skip
    assert g.width == pytest.approx(wall)
    assert g.tcp[0, 3] == pytest.approx(r - wall / 2)
    assert rim_pinch_refusal(t, "body", "on", "front", "back") is None
    assert ("canGraspFrom", t.name, "body", "on", "front", "back") in object_facts(t, True)
    # a body the hand wraps is no rim (the paper's grasp, decoded as before)
    narrow = next(x for s in range(40) if _lifts(x := generate("tumbler", "v1", s), False))
    assert rim_strip(narrow, "body", "on", "front") is None
    assert rim_pinch_refusal(narrow, "body", "on", "front", "back").rule == "rim"


def test_a_heavy_saucepan_is_refused_by_its_mass_a_frying_pan_by_its_moment():
    heavy = next(
        t for s in range(40) if (t := generate("saucepan", "v1", s)).mass > 1.1 and t.mass < 1.5
    )
    assert rim_pinch_refusal(heavy, "body", "on", "front", "back").rule == "rim-payload"
    pan = generate("frying-pan", "v1", 1)
    refusal = rim_pinch_refusal(pan, "body", "on", "front", "back")
    assert refusal.rule == "rim-flare" and "pivot" in refusal.detail
    light = next(t for s in range(40) if (t := generate("saucepan", "v1", s)).mass < 0.6)
    assert rim_pinch_refusal(light, "body", "on", "left", "right") is None  # upright walls


def _torque_refused_board() -> Any:
    return next(
        t
        for s in range(40)
        if (
            r := pick_refusal(
                t := generate("paddle-board", "v1", s), "handle", "on", "left", "right"
            )
        )
        and r.rule == "torque"
    )


def test_a_board_too_heavy_at_its_handle_for_the_paper_rules_is_lifted_in_the_extended():
    board = _torque_refused_board()
    assert not _lifts(board, False)
    assert ("canLift", board.name, "handle") in object_facts(board, True)
    moment = pick_refusal(board, "handle", "on", "left", "right").values["moment"]
    assert 1.4 < moment <= 2.4


def test_a_tray_held_at_an_end_handle_along_its_lever_keeps_the_paper_limit():
    from utamp_gym.affordances.hand import hold_refusal

    tray = next(
        t
        for s in range(40)
        if (r := hold_refusal(t := generate("tray", "v1", s), "handle-front", "on"))
        and 1.4 < r.values["moment"] <= 2.4
    )
    # the fingers close along x, the lever runs along x: the paper's limit
    assert hold_refusal(tray, "handle-front", "on", extended=True, finger="front").rule == "torque"
    assert ("canLift", tray.name, "handle-front") not in object_facts(tray, True)


def test_the_extended_domain_is_the_paper_domain_by_another_name_and_the_edge_actions():
    """utamp2x is utamp2 renamed, with two more static predicates and the edge actions
    appended (`tests/test_edge_slide.py`): the paper's three actions are unchanged."""
    assert "utamp2x" in DOMAINS
    paper, extended = domain_text("utamp2"), domain_text("utamp2x")
    body = extended[extended.index("(define") :]
    renamed = paper[paper.index("(define") :].replace("(domain utamp2)", "(domain utamp2x)")
    preds_end = renamed.index("?o2-o1 - part))") + len("?o2-o1 - part)")
    assert body.startswith(renamed[:preds_end])
    head, _, rest = body[preds_end:].partition("\n  ; Grasp ?obj1")
    assert "canEdgePinch" in head and "canSlideEdge" in head and ":action" not in head
    paper_actions = renamed[renamed.index("\n  ; Grasp ?obj1") : renamed.rindex(")")].rstrip()
    assert ("\n  ; Grasp ?obj1" + rest).startswith(paper_actions)
    assert "(:action slide-edge" in rest and "(:action place-edge" in rest


# ------------------------------------------------------------------ scenes
def _lone(table: dict[str, Any], tray: bool = False) -> Any:
    """`table` alone on slot1 of the benchmarks' two-slot table (`grasp_coverage.lone_data`;
    `tray`: a wooden tray on slot2, the goal's base)."""
    data = grasp_coverage.lone_data(table)
    if tray:
        data["objects"].append({"name": "tray", "type": "wooden-tray", "on": "slot2"})
        data["goal_base"] = "tray"
    return scene_from_dict(data)


def _bowl_on_a_tray() -> tuple[Any, tuple[str, ...]]:
    """A plastic bowl alone with a tray, and its utamp2x-rules plan (checked)."""
    f = family("bowl")
    scene = _lone(type_table(f, extremes(f, "plastic", False)), tray=True)
    assert not plan_scene(scene, "utamp2-rules").solved
    plan = plan_scene(scene, "utamp2x-rules").plan
    assert plan and plan[0].startswith("(pick-support obj obj-")
    member, palm, f1, f2 = plan[0].strip("()").split()[2:6]
    grasp = ("canGraspFrom", "obj", member.removeprefix("obj-"), palm, f1, f2)
    bowl = scene.type_of("obj")
    assert grasp in object_facts(bowl, True) and grasp not in object_facts(bowl, False)
    return scene, plan


def test_a_bowl_on_a_tray_is_planned_in_the_extended_domain_only() -> None:
    _bowl_on_a_tray()


@physics
def test_the_extended_plan_puts_the_bowl_on_the_tray_in_physics():
    from utamp_gym.agents.runs import execute_plan

    scene, plan = _bowl_on_a_tray()
    run = execute_plan(scene, plan, seed=0, pose_noise=0.0)
    assert run.success, run.failure_reason


# ------------------------------------------------------------------ physics
def _turn(sim: Any, yaw: float) -> None:
    """Turn the object about the vertical by `yaw` where it stands."""
    import mujoco

    st = sim.state
    m, d = st.world.model, st.data
    adr = m.jnt_qposadr[m.body_jntadr[st.world.body_ids["obj"]]]
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, np.array([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]),
                       d.qpos[adr + 3 : adr + 7].copy())  # fmt: skip
    d.qpos[adr + 3 : adr + 7] = out
    d.qvel[:] = 0
    mujoco.mj_forward(m, d)


def _pick_and_place(sim: Any, table: dict[str, Any], grasp: str, yaw: float = 0.0) -> str:
    sim.reset(_lone(table), np.random.default_rng(0))
    _turn(sim, yaw)
    picked = sim.execute(f"(pick-support obj obj-{grasp} under on slot1 under on)")
    if not picked.success:
        return picked.reason or "pick failed"
    placed = sim.execute(f"(place-support obj obj-{grasp} under on under slot2 under on)")
    return "" if placed.success else placed.reason or "place failed"


@pytest.fixture(scope="module")
def sim():
    from utamp_gym.sim.backend import MujocoBackend

    backend = MujocoBackend(pose_noise=0.0)
    yield backend
    backend.close()


def _extremes(fam: str) -> list[tuple[str, bool]]:
    return [(mat, high) for mat, _ in family(fam).materials for high in (False, True)]


@physics
@pytest.mark.parametrize("yaw", YAWS[1:2])
def test_a_thin_steel_bowl_is_lifted_by_its_rim(sim, yaw):
    f = family("bowl")
    assert (
        rim_pinch_refusal(extreme_type("bowl", "steel", False), "rim-front", "on", "front", "back")
        is None
    )
    assert (
        _pick_and_place(
            sim, type_table(f, extremes(f, "steel", False)), "rim-front on front back", yaw
        )
        == ""
    )


@physics
@pytest.mark.slow
@pytest.mark.parametrize(("mat", "high"), _extremes("bowl"))
def test_bowls_at_their_extremes_are_lifted_by_a_rim_pinch_at_any_yaw(sim, mat, high):
    f = family("bowl")
    t = extreme_type("bowl", mat, high)
    assert rim_pinch_refusal(t, "rim-front", "on", "front", "back") is None  # the rule grants
    table = type_table(f, extremes(f, mat, high))
    for yaw in YAWS:
        assert _pick_and_place(sim, table, "rim-front on front back", yaw) == "", (mat, high, yaw)


@physics
@pytest.mark.parametrize(("mat", "high"), _extremes("plate"))
def test_a_plate_is_lifted_by_its_rim(sim, mat, high):
    f = family("plate")
    t = extreme_type("plate", mat, high)
    # the 1.2 kg ceramic plate's rim is thick enough for the full squeeze
    # (`hand.MIN_PINCH`): granted up to `calibrated.EXTENDED_LIFT_LIMIT`
    assert rim_pinch_refusal(t, "rim-back", "on", "front", "back") is None
    assert (
        _pick_and_place(sim, type_table(f, extremes(f, mat, high)), "rim-back on front back") == ""
    )


@physics
def test_the_board_is_lifted_by_its_handle_in_physics(sim):
    from utamp_gym.kitchenware.params import draw

    board = _torque_refused_board()
    seed = int(board.name.rsplit("-", 1)[1])
    f = family("paddle-board")
    assert _pick_and_place(sim, type_table(f, draw(f, "v1", seed)), "handle on left right") == ""


@physics
def test_a_frying_pan_the_rules_refuse_pivots_out_of_the_pinch(sim):
    f = family("frying-pan")
    from utamp_gym.kitchenware.params import draw

    assert rim_pinch_refusal(generate("frying-pan", "v1", 1), "body", "on", "front", "back")
    why = _pick_and_place(sim, type_table(f, draw(f, "v1", 1)), "body on front back")
    assert "not liftable" in why and "pivoted" in why
