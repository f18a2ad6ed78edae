"""An object reaching far out of the hand turns in it while carried: the pads' hold creeps
under its weight's moment even below the rules' torque limit. It is lifted with room for
that (`measure.turn_sink`) and carried with its turned pose in the collision model
(`measure.turned_in_hand`, `CollisionChecker.attach(..., also=...)`). Without that a paddle
board held by its handle turned 4.4 deg on its way over a tumbler standing on a mug
(procedural-v1/test-count/0086, seed 1) and knocked it over."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from poses import DOWN, top_down

from utamp_gym.affordances.solids import centre_of_mass
from utamp_gym.kitchenware import generate
from utamp_gym.sim.decode import box_corners
from utamp_gym.sim.measure import CARRY_TILT_DEG, sweep_reach, turn_sink, turned_in_hand


def _held_by_handle(board) -> np.ndarray:
    """tcp_T_obj of a board lying flat, held top-down at the middle of its handle's top."""
    h = board.members["handle"].box
    grip = np.array([(h.min[0] + h.max[0]) / 2, (h.min[1] + h.max[1]) / 2, h.max[2] - 0.01])
    out = np.eye(4)
    out[:3, :3] = DOWN.T  # the object upright under a top-down hand
    out[:3, 3] = -DOWN.T @ grip
    return out


def _bottom(t, pose: np.ndarray) -> float:
    return float((box_corners(t.bbox) @ pose[:3, :3].T + pose[:3, 3])[:, 2].min())


def test_a_board_held_by_its_handle_turns_its_far_end_down():
    board = generate("paddle-board", "v1", 688711848)  # 0086's obj2
    tcp = top_down([0.45, -0.2, 0.3])
    held = _held_by_handle(board)
    turned = turned_in_hand(board, tcp, held)
    angle = math.degrees(math.acos((np.trace(held[:3, :3].T @ turned[:3, :3]) - 1) / 2))
    assert angle == pytest.approx(CARRY_TILT_DEG, abs=1e-6)
    # the TCP stays where it is in the hand: a turn about the grasp
    np.testing.assert_allclose(turned[:3, :3] @ -held[:3, :3].T @ held[:3, 3], -turned[:3, 3])
    # its lowest point sinks by about its reach's sine (the far corner goes down)
    sink = _bottom(board, tcp @ held) - _bottom(board, tcp @ turned)
    assert turn_sink(board, "handle") == pytest.approx(
        sweep_reach(board, "handle") * math.sin(math.radians(CARRY_TILT_DEG))
    )
    assert 0.8 * turn_sink(board, "handle") < sink < 1.05 * turn_sink(board, "handle")
    # the board lies along x with its handle at -x: its far end is +x, and goes down
    far = np.array([board.bbox.max[0], 0.0, board.bbox.min[2], 1.0])
    assert (tcp @ turned @ far)[2] < (tcp @ held @ far)[2] - 0.8 * turn_sink(board, "handle")


def test_an_object_centred_under_the_hand_does_not_turn():
    mug = generate("mug", "v1", 3)
    cx, cy = centre_of_mass(mug)
    held = np.eye(4)
    held[:3, :3] = DOWN.T
    held[:3, 3] = -DOWN.T @ np.array([cx, cy, mug.bbox.max[2]])  # its centre under the TCP
    np.testing.assert_allclose(turned_in_hand(mug, top_down([0.4, 0.0, 0.3]), held), held)


@pytest.fixture(scope="module")
def arm():
    """Panda at the origin, a 36 cm board loose on the floor and a 'tumbler' block."""
    from utamp_gym.robot.collision import CollisionChecker
    from utamp_gym.robot.kinematics import HOME_Q, PandaKinematics
    from utamp_gym.robot.panda_mjcf import add_panda, apply_recommended_options, set_home

    world = mujoco.MjSpec()
    apply_recommended_options(world)
    board = world.worldbody.add_body(name="board", pos=[-0.5, 0.5, 0.01])
    board.add_freejoint()
    board.add_geom(
        name="board_geom", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.18, 0.1, 0.01], mass=1.0
    )
    # its top 2 cm below the board's bottom where the board's far end passes
    world.worldbody.add_geom(
        name="tumbler", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.03, 0.03, 0.1], pos=[0.75, 0, 0.1]
    )
    handles = add_panda(world)
    model = world.compile()
    ids = handles.bind(model)
    data = mujoco.MjData(model)
    set_home(model, data, ids)
    checker = CollisionChecker(model, ids, margin=0.01)
    checker.sync(data)
    q = (
        PandaKinematics()
        .ik(top_down([0.45, 0.0, 0.23]), np.array(HOME_Q), np.random.default_rng(1))
        .q
    )
    return model, checker, q


@pytest.mark.physics
def test_the_checker_counts_the_held_object_at_its_turned_pose(arm):
    """A board held 2 cm over a block (beyond the 1 cm margin) is clear; turned 10 deg
    about the grasp, its far end reaches into the block."""
    model, checker, q = arm
    board = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "board")
    tcp = checker.tcp_pose(q)
    held = np.eye(4)  # upright, its centre 16 cm along +x from the TCP, at its height
    held[:3, :3] = tcp[:3, :3].T
    held[:3, 3] = tcp[:3, :3].T @ np.array([0.16, 0.0, 0.0])
    world = tcp @ held
    assert world[0, 3] == pytest.approx(0.61, abs=0.005)
    assert world[2, 3] - 0.01 - 0.2 == pytest.approx(0.02, abs=0.005)  # 2 cm over the block
    a = math.radians(CARRY_TILT_DEG)  # about world +y: the far end (+x) goes down
    ry = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    turned = held.copy()
    turned[:3, :] = tcp[:3, :3].T @ ry @ tcp[:3, :3] @ held[:3, :]
    assert (tcp @ turned)[2, 3] < world[2, 3] - 0.02
    checker.attach(board, held)
    try:
        assert checker.is_valid(q)
        checker.attach(board, held, also=(turned,))
        assert not checker.is_valid(q)
        assert "tumbler" in checker.describe(checker.contacts(q))
        checker.attach(board, held)  # a new attachment forgets the other poses
        assert checker.is_valid(q)
    finally:
        checker.detach()


@pytest.mark.physics
def test_the_board_passes_over_the_stack_on_procedural_v1(monkeypatch):
    """procedural-v1/test-count/0086 seed 1, step 5: the board comes over the tumbler on the
    mug; without the room to turn it sinks onto the tumbler and knocks the stack over."""
    from utamp_gym.agents.runs import run_episode
    from utamp_gym.sim import skills

    scene = "procedural-v1/test-count/0086"
    result = run_episode(scene, "utamp2-rules", 1)
    assert result.success, result.failure
    monkeypatch.setattr(skills, "turn_sink", lambda t, member: 0.0)
    monkeypatch.setattr(skills, "turned_in_hand", lambda t, tcp, pose: None)
    result = run_episode(scene, "utamp2-rules", 1)
    assert not result.success and result.failure is not None
    assert result.failure["step"] == 5 and "toppled" in result.failure["reason"]
