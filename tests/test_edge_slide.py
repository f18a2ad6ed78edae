"""Boards slid to the table's edge and pinched there (the extended domain's ``slide-edge`` and
``place-edge``, issue #39): the rule's decision from geometry, the plans it makes possible,
and the decision checked against physics (a handleless board slid, lifted and put on the
other slot; a paddle board the rule refuses for its moment slips).

The physics tests look only at what the simulation measured (the skills' own checks)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from utamp_gym.affordances.edge import (
    COM_MARGIN,
    DEEP_PAD_IN,
    EDGE_GRASP,
    OVERHANG,
    PAD_IN,
    edge_depth,
    edge_pinch_refusal,
    edge_torque_limit,
)
from utamp_gym.affordances.hand import G
from utamp_gym.affordances.rules import derive_affordances, object_facts
from utamp_gym.affordances.solids import centre_of_mass
from utamp_gym.kitchenware import family, generate, type_table
from utamp_gym.kitchenware.params import draw
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.catalogue import Member
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.sim.decode import parse_action

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_scripts"))
import readme

grasp_coverage = readme.load_script("benchmarks/grasp_coverage.py")
physics = pytest.mark.physics
SLIDE = "(slide-edge obj obj-body back on under back on slot1 under on)"
PLACE = "(place-edge obj obj-body back on under back on under slot2 back on)"


def _scene(fam: str, seed: int, goal: bool = True) -> Any:
    """Instance `seed` of `fam` alone on slot1 of a two-slot table, the benchmarks' scene
    (`grasp_coverage.lone_data`; goal: on slot2)."""
    table = type_table(family(fam), draw(family(fam), "v1", seed))
    data = grasp_coverage.lone_data(table, f"edge-{fam}-{seed}")
    if goal:
        data["goal"] = {"atoms": ["(oc under obj slot2)"]}
    return scene_from_dict(data)


# ------------------------------------------------------------------ the rule
def test_a_handleless_board_is_granted_the_edge_pinch_only_in_the_calibrated_extended_domain():
    board = generate("chopping-board", "v1", 1)
    assert not any(f[0] in ("canLift", "canGraspFrom") for f in object_facts(board, True))
    assert edge_pinch_refusal(board) is None
    assert ("canEdgePinch", board.name, *EDGE_GRASP) in object_facts(board, True)
    assert not any(f[0] == "canEdgePinch" for f in object_facts(board, False))
    # the rules before the calibration (calibrated=False) have none
    assert not any(f[0] == "canEdgePinch" for f in object_facts(board, True, calibrated=False))


def test_the_rule_decides_from_geometry_not_from_a_name():
    board = generate("chopping-board", "v1", 1)
    renamed = board._replace(name="mystery-slab")
    assert edge_pinch_refusal(renamed) is None
    # too thick for the opening once it is 7 cm tall
    box = generate("food-box", "v1", 0)
    assert edge_pinch_refusal(box) is not None
    # a plate stands on a foot smaller than its body: its back end is no solid slab
    assert edge_pinch_refusal(generate("plate", "v1", 0)).rule == "edge-slab"


def test_the_moment_about_the_pinch_bounds_the_lift_by_the_boards_thickness():
    boards = [generate("paddle-board", "v1", s) for s in range(40)]
    refused = [(t, r) for t in boards if (r := edge_pinch_refusal(t)) is not None]
    assert refused and all(r.rule == "torque" for _, r in refused)
    assert all(r.values["moment"] > edge_torque_limit(t.bbox.size[2]) for t, r in refused)
    # the pads' friction couple grows with the thickness they close across
    assert edge_torque_limit(0.01) < edge_torque_limit(0.02) < edge_torque_limit(0.03)


def test_a_board_that_turns_out_of_a_shallow_pinch_is_pinched_deeper_nearer_its_centre():
    board = generate("paddle-board", "v1", 1)  # 1.26 kg, its handle at the back end
    cx, _ = centre_of_mass(board)
    x0, thick = float(board.bbox.min[0]), float(board.bbox.size[2])
    assert board.mass * G * (cx - x0 - PAD_IN) > edge_torque_limit(thick)  # shallow: turns
    assert edge_depth(board) == DEEP_PAD_IN
    assert edge_pinch_refusal(board) is None
    # a board the shallow pinch holds keeps it (the slide and pinch as before)
    assert edge_depth(generate("paddle-board", "v1", 0)) == PAD_IN
    # deeper is not enough for every board: its moment still refuses it
    refusal = edge_pinch_refusal(generate("paddle-board", "v1", 27))
    assert refusal is not None and refusal.rule == "torque"


def test_the_centre_of_mass_must_stay_on_the_table_while_the_board_overhangs():
    board = generate("chopping-board", "v1", 1)
    half = OVERHANG + COM_MARGIN - 0.005  # a slab this short would tip off the edge
    body = Member("body", "body", Box((-half, -0.12, 0.0), (half, 0.12, 0.03)))
    parts = {**board.parts, "under": board.parts["under"]._replace(size=(2 * half, 0.24))}
    short = board._replace(members={"body": body}, parts=parts)
    refusal = edge_pinch_refusal(short)
    assert refusal is not None and refusal.rule == "edge-com"
    assert refusal.values["inside"] == pytest.approx(half - OVERHANG)
    longer = Member("body", "body", Box((-2 * half, -0.12, 0.0), (2 * half, 0.12, 0.03)))
    parts = {**board.parts, "under": board.parts["under"]._replace(size=(4 * half, 0.24))}
    assert edge_pinch_refusal(board._replace(members={"body": longer}, parts=parts)) is None


def test_slide_edge_facts_come_from_a_fixed_flat_top_and_plans_use_them():
    scene = _scene("chopping-board", 1)
    facts = derive_affordances([scene.type_of("obj"), scene.table], extended=True)
    assert any(f[0] == "canSlideEdge" for f in facts)
    assert not plan_scene(scene, "utamp2-rules").solved
    plan = plan_scene(scene, "utamp2x-rules").plan
    assert [a.split()[0] for a in plan] == ["(slide-edge", "(place-edge"]
    acts = [parse_action(a, scene) for a in plan]
    assert acts[0].support == "slot1" and acts[1].support == "slot2"


# ------------------------------------------------------------------ physics
def _run(fam: str, seed: int, actions: tuple[str, ...], rng: int | None = None) -> list[Any]:
    from utamp_gym.sim.backend import MujocoBackend

    sim = MujocoBackend(pose_noise=0.002)
    try:
        sim.reset(
            _scene(fam, seed, goal=False), np.random.default_rng(seed if rng is None else rng)
        )
        out = []
        for a in actions:
            out.append(sim.execute(a))
            if not out[-1].success:
                break
        out.append(sim.object_poses()["obj"])
        return out
    finally:
        sim.close()


@physics
def test_a_handleless_board_is_slid_to_the_edge_lifted_and_put_on_the_other_slot():
    assert edge_pinch_refusal(generate("chopping-board", "v1", 1)) is None  # the rule allows
    slid, placed, pose = _run("chopping-board", 1, (SLIDE, PLACE))
    assert slid.success, slid.reason
    assert placed.success, placed.reason
    assert np.linalg.norm(pose[:2] - np.array([0.5, 0.3])) < 0.03  # on slot2, flat
    assert abs(pose[2]) < 0.005


@physics
def test_a_board_the_rule_refuses_for_its_moment_slips_in_the_pads():
    refusal = edge_pinch_refusal(generate("paddle-board", "v1", 27))
    assert refusal is not None and refusal.rule == "torque"
    slid, _ = _run("paddle-board", 27, (SLIDE,), rng=1)  # (rng 27: the noisy slide falls short)
    assert not slid.success
    assert "not liftable" in (slid.reason or "")


@physics
def test_a_board_pinched_deeper_is_lifted_and_put_on_the_other_slot():
    board = generate("paddle-board", "v1", 1)
    assert edge_depth(board) == DEEP_PAD_IN and edge_pinch_refusal(board) is None
    slid, placed, pose = _run("paddle-board", 1, (SLIDE, PLACE))
    assert slid.success, slid.reason
    assert placed.success, placed.reason
    assert abs(pose[1] - 0.3) < 0.03  # on slot2 (its handle shifts its origin along x)


@pytest.mark.parametrize("grounding", ["symbolic", pytest.param("physics", marks=physics)])
def test_the_env_takes_the_edge_actions_in_the_extended_domain(tmp_path: Any, grounding: str):
    """A bread board of a scene file (the env's ``board`` row) reaches the other slot through
    the env's action strings, as planned (slide-edge, place-edge)."""
    import tomli_w

    from utamp_gym.env.kitchen import UTampKitchenEnv

    table = type_table(family("chopping-board"), draw(family("chopping-board"), "v1", 1))
    scene = {
        "name": "edge-board", "types": {"bread-board": table},
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "slots": [
            {"name": "slot1", "position": [0.5, -0.18], "min": [0.2, -0.5], "max": [0.8, 0.08]},
            {"name": "slot2", "position": [0.5, 0.3], "min": [0.2, 0.08], "max": [0.8, 0.6]},
        ],
        "objects": [{"name": "board", "type": "bread-board", "on": "slot1"}],
        "goal_base": "board", "goal": {"atoms": ["(oc under board slot2)"]},
    }  # fmt: skip
    path = tmp_path / "edge-board.toml"
    path.write_text(tomli_w.dumps(scene))
    env = UTampKitchenEnv(
        grounding=grounding, scene=str(path), domain="utamp2x", affordances="rules"
    )
    try:
        env.reset(seed=0)
        plan = [SLIDE.replace("obj ", "board ").replace("obj-", "board-"),
                PLACE.replace("obj ", "board ").replace("obj-", "board-")]  # fmt: skip
        assert set(plan) <= set(env.universe.actions)
        rewards = []
        for action in plan:
            _, reward, terminated, _, _ = env.step(env.universe.action_index[action])
            rewards.append(reward)
        assert rewards == [0.0, 1.0] and terminated
    finally:
        env.close()
