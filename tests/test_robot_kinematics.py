"""Pinocchio kinematics of the Panda: IK round trips, limits, accept callback, assets."""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.robot.assets import panda_assets, srdf_disabled_collisions
from utamp_gym.robot.kinematics import (
    HOME_Q,
    PandaKinematics,
    matrix_to_quat_wxyz,
    pose_matrix,
)

pytestmark = pytest.mark.physics


@pytest.fixture(scope="module")
def kin() -> PandaKinematics:
    return PandaKinematics()


def _rot_err(a: np.ndarray, b: np.ndarray) -> float:
    cos = (np.trace(a[:3, :3].T @ b[:3, :3]) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


def _top_down(reach: float, bearing_deg: float, height: float) -> np.ndarray:
    """A TCP pose pointing straight down, `reach` m from the base at `bearing_deg`, `height` m
    above the table; the gripper's fingers across the radial direction."""
    b = np.radians(bearing_deg)
    target = np.eye(4)
    target[:3, :3] = np.array(
        [[np.cos(b), np.sin(b), 0.0], [np.sin(b), -np.cos(b), 0.0], [0.0, 0.0, -1.0]]
    )
    target[:3, 3] = [reach * np.cos(b), reach * np.sin(b), height]
    return target


def test_assets_found():
    assets = panda_assets()
    assert assets.urdf.is_file() and assets.srdf.is_file()
    assert assets.collision_mesh("link3").is_file()
    uri = "package://example-robot-data/robots/panda_description/meshes/collision/hand.stl"
    assert assets.resolve_uri(uri).is_file()
    pairs = srdf_disabled_collisions(assets)
    assert ("panda_link0", "panda_link1") in pairs


def test_model_is_the_7_dof_arm(kin):
    assert kin.model.nq == 7
    assert kin.within_limits(np.array(HOME_Q))
    np.testing.assert_allclose(kin.effort_limit, [87] * 4 + [12] * 3)


def test_fk_of_ik_matches_random_reachable_targets(kin):
    rng = np.random.default_rng(123)
    for _ in range(30):
        target = kin.fk(kin.random_q(rng))
        seed = kin.random_q(rng)  # a different configuration than the one that made the target
        res = kin.ik(target, seed, rng)
        assert res.success, res
        assert kin.within_limits(res.q)
        reached = kin.fk(res.q)
        assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) < 1e-3
        assert _rot_err(reached, target) < 1.0
        assert res.iterations >= 1 and res.attempts >= 1 and res.time > 0


def test_ik_accepts_pos_quat_and_first_attempt_uses_seed(kin):
    rng = np.random.default_rng(0)
    q_goal = np.array(HOME_Q) + 0.05
    pos, quat = kin.fk_pose(q_goal)
    np.testing.assert_allclose(pose_matrix(pos, quat), kin.fk(q_goal), atol=1e-12)
    res = kin.ik((pos, quat), np.array(HOME_Q), rng)
    assert res.success and res.attempts == 1  # converges from a nearby seed, no restart
    assert np.allclose(matrix_to_quat_wxyz(kin.fk(res.q)[:3, :3]), quat, atol=1e-3)


def test_ik_accept_callback_filters_solutions(kin):
    rng = np.random.default_rng(5)
    target = kin.fk(np.array(HOME_Q))
    seen: list[np.ndarray] = []

    def accept(q: np.ndarray) -> bool:
        seen.append(q)
        return len(seen) >= 2  # refuse the first converged solution

    res = kin.ik(target, np.array(HOME_Q), rng, accept=accept)
    assert res.success and res.rejected == 1 and res.attempts >= 2
    never = kin.ik(target, np.array(HOME_Q), rng, accept=lambda q: False, max_attempts=3)
    assert not never.success and 1 <= never.rejected <= 3


def test_ik_unreachable_target_fails_cleanly(kin):
    rng = np.random.default_rng(1)
    target = np.eye(4)
    target[:3, 3] = [2.0, 0.0, 0.5]  # 2 m away: out of reach
    res = kin.ik(target, np.array(HOME_Q), rng, max_attempts=3)
    assert not res.success and res.pos_error > 0.5 and kin.within_limits(res.q)


def test_same_generator_seed_same_ik_solution(kin):
    target = kin.fk(kin.random_q(np.random.default_rng(9)))
    seed = np.array(HOME_Q)
    a = kin.ik(target, seed, np.random.default_rng(4))
    b = kin.ik(target, seed, np.random.default_rng(4))
    np.testing.assert_array_equal(a.q, b.q)


@pytest.mark.parametrize("height", [0.02, 0.35])
@pytest.mark.parametrize("bearing_deg", [-40.0, 0.0, 40.0])
def test_the_hand_reaches_from_above_as_far_as_placements_keep_members(kin, height, bearing_deg):
    """Placements on a slot keep every member's centre within `MEMBER_REACH` of the base so
    that it can be picked and lifted again: the TCP pointing straight down reaches that far
    (at the table and 35 cm above it, across the table's front), and FK(IK(x)) = x."""
    from utamp_gym.sim.placement import MEMBER_REACH

    target = _top_down(MEMBER_REACH, bearing_deg, height)
    res = kin.ik(target, HOME_Q, np.random.default_rng(0), max_attempts=40)
    assert res.success, (bearing_deg, height, res.pos_error)
    np.testing.assert_allclose(kin.fk(res.q)[:3, 3], target[:3, 3], atol=2e-4)


@pytest.mark.parametrize("height", [0.0, 0.15, 0.3])
@pytest.mark.parametrize("bearing_deg", [-60.0, 0.0, 60.0])
def test_the_hand_reaches_from_above_as_far_as_top_down_reach_and_no_farther(
    kin, height, bearing_deg
):
    """`TOP_DOWN_REACH` is this arm's reach with the TCP pointing straight down, from the
    table to 30 cm above it: a placement on an object keeps every member within it, so that
    the arm can pick the object up again. 3 cm farther, no configuration reaches."""
    from utamp_gym.robot.kinematics import TOP_DOWN_REACH

    for reach, reached in ((TOP_DOWN_REACH, True), (TOP_DOWN_REACH + 0.03, False)):
        target = _top_down(reach, bearing_deg, height)
        res = kin.ik(target, HOME_Q, np.random.default_rng(0), max_attempts=40)
        assert res.success is reached, (reach, bearing_deg, height, res.pos_error)
