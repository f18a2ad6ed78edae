"""Collision checking (with a held object) and OMPL motion planning for the Panda arm."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from poses import top_down

from utamp_gym.errors import GroundingError
from utamp_gym.robot import motion
from utamp_gym.robot.collision import CollisionChecker
from utamp_gym.robot.kinematics import HOME_Q, PandaKinematics
from utamp_gym.robot.motion import (
    PANDA_ACC_LIMITS,
    PANDA_VEL_LIMITS,
    dense_check,
    interpolate_path,
    plan_motion,
    time_parameterize,
)
from utamp_gym.robot.panda_mjcf import add_panda, apply_recommended_options, set_home

pytestmark = pytest.mark.physics

TABLE_TOP = 0.3


@pytest.fixture(scope="module")
def scene():
    """Panda at the origin, a table, a wall across it, and a loose 6 cm box on the floor."""
    world = mujoco.MjSpec()
    apply_recommended_options(world)
    world.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    world.worldbody.add_geom(
        name="table",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.3, 0.5, TABLE_TOP / 2],
        pos=[0.55, 0, TABLE_TOP / 2],
    )
    world.worldbody.add_geom(
        name="wall", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.15, 0.02, 0.2], pos=[0.5, 0, 0.5]
    )
    box = world.worldbody.add_body(name="box", pos=[-0.5, 0.5, 0.03])
    box.add_freejoint()
    box.add_geom(name="box_geom", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.03] * 3, mass=0.2)
    handles = add_panda(world)
    model = world.compile()
    ids = handles.bind(model)
    data = mujoco.MjData(model)
    set_home(model, data, ids)
    kin = PandaKinematics()
    checker = CollisionChecker(model, ids, margin=0.01)
    checker.sync(data)
    rng = np.random.default_rng(0)
    q_a = kin.ik(top_down([0.5, -0.2, 0.45]), np.array(HOME_Q), rng, accept=checker.is_valid).q
    q_b = kin.ik(top_down([0.5, 0.2, 0.45]), np.array(HOME_Q), rng, accept=checker.is_valid).q
    return model, data, ids, kin, checker, q_a, q_b


def _exact_checker(scene) -> CollisionChecker:
    model, data, ids, *_ = scene
    exact = CollisionChecker(model, ids, margin=0.0, self_margin=0.0)
    exact.sync(data)
    return exact


def test_straight_line_through_wall_collides(scene):
    *_, checker, q_a, q_b = scene
    assert checker.is_valid(q_a) and checker.is_valid(q_b)
    line = interpolate_path(np.stack([q_a, q_b]), 0.02)
    assert not all(checker.is_valid(q) for q in line)
    assert dense_check(np.stack([q_a, q_b]), checker, 0.01) == 1


def test_planned_path_is_collision_free_under_dense_recheck(scene):
    *_, checker, q_a, q_b = scene
    exact = _exact_checker(scene)
    for seed in range(3):
        plan = plan_motion(checker, q_a, q_b, np.random.default_rng(seed))
        assert not plan.direct and len(plan.vertices) >= 3
        np.testing.assert_allclose(plan.waypoints[0], q_a)
        np.testing.assert_allclose(plan.waypoints[-1], q_b)
        assert np.abs(np.diff(plan.waypoints, axis=0)).max() <= 0.02 + 1e-9
        assert dense_check(plan.waypoints, exact, 0.002) is None
        assert dense_check(plan.waypoints, checker, 0.02) is None


def test_same_generator_seed_gives_identical_path(scene):
    *_, checker, q_a, q_b = scene
    first = plan_motion(checker, q_a, q_b, np.random.default_rng(42))
    second = plan_motion(checker, q_a, q_b, np.random.default_rng(42))
    np.testing.assert_array_equal(first.waypoints, second.waypoints)


def test_the_planner_limit_is_counted_in_checks_not_seconds(scene, monkeypatch):
    """A budget of 40 collision checks (~2.4 ms at CHECK_S) cannot get round the wall: the
    failure comes after exactly that many RRTConnect checks, on a slow machine too (here: a
    clock that jumps 10 ms per reading would have ended a timed search at once)."""
    *_, checker, q_a, q_b = scene
    with pytest.raises(GroundingError, match=r"in 40 collision checks \(~0\.00 s"):
        plan_motion(checker, q_a, q_b, np.random.default_rng(0), timeout=40 * motion.CHECK_S)
    clock = iter(np.arange(1e6) * 0.01)
    monkeypatch.setattr(motion.time, "perf_counter", lambda: float(next(clock)))
    plan = plan_motion(checker, q_a, q_b, np.random.default_rng(42))
    reference = plan_motion(checker, q_a, q_b, np.random.default_rng(42))
    np.testing.assert_array_equal(plan.waypoints, reference.waypoints)
    assert not plan.direct


def test_free_straight_line_skips_the_sampler(scene):
    *_, kin, checker, q_a, _ = scene
    rng = np.random.default_rng(2)
    q_near = kin.ik(top_down([0.45, -0.25, 0.5]), q_a, rng, accept=checker.is_valid).q
    plan = plan_motion(checker, q_a, q_near, np.random.default_rng(0))
    assert plan.direct and len(plan.vertices) == 2


def test_held_object_counts_in_collision_checks(scene):
    model, _, _, kin, checker, *_ = scene
    box = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "box")
    q = kin.ik(
        top_down([0.45, -0.3, TABLE_TOP + 0.1]), np.array(HOME_Q), np.random.default_rng(1)
    ).q
    assert checker.is_valid(q)  # bare arm: TCP 10 cm above the table
    tcp_t_box = np.eye(4)
    tcp_t_box[2, 3] = 0.076  # box centre 7.6 cm below the TCP: its bottom 6 mm into the table
    checker.attach(box, tcp_t_box)
    try:
        hits = checker.contacts(q)
        assert hits and any(c.kind == "world" for c in hits)
        assert any(model.geom_bodyid[c.geom1] == box for c in hits)
        assert "box_geom" in checker.describe(hits)
        # Touching the hand does not count: a box centred on the TCP sits between the fingers.
        checker.attach(box, np.eye(4))
        assert checker.is_valid(q)
    finally:
        checker.detach()
    assert checker.is_valid(q)


def test_start_inside_margin_is_tolerated(scene):
    """A held box resting on the table (inside the margin) can still be lifted away."""
    model, _, _, kin, checker, *_ = scene
    box = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "box")
    rng = np.random.default_rng(3)
    q_rest = kin.ik(top_down([0.45, -0.3, TABLE_TOP + 0.03]), np.array(HOME_Q), rng).q
    q_up = kin.ik(top_down([0.45, -0.3, TABLE_TOP + 0.2]), q_rest, rng).q
    checker.attach(box, np.eye(4))  # box bottom touches the table top
    try:
        assert not checker.is_valid(q_rest)
        plan = plan_motion(checker, q_rest, q_up, rng)
        exact = _exact_checker(scene)
        exact.attach(box, np.eye(4))
        with exact.tolerating(q_rest):  # the resting contact may stay, not deepen
            assert dense_check(plan.waypoints, exact, 0.005) is None
        assert checker.tolerance == {}  # relaxation only lasts for the call
        too_deep = kin.ik(top_down([0.45, -0.3, TABLE_TOP + 0.01]), q_rest, rng).q
        with pytest.raises(GroundingError, match="in collision"):
            plan_motion(checker, too_deep, q_up, rng)
    finally:
        checker.detach()


def test_time_parameterization_respects_limits_and_ends_on_goal(scene):
    *_, checker, q_a, q_b = scene
    plan = plan_motion(checker, q_a, q_b, np.random.default_rng(0))
    vel, acc, dt = PANDA_VEL_LIMITS * 0.5, PANDA_ACC_LIMITS * 0.3, 0.002
    traj = time_parameterize(plan.waypoints, vel, acc, dt)
    np.testing.assert_allclose(traj[-1], q_b, atol=1e-12)
    steps = np.diff(np.vstack([q_a, traj]), axis=0) / dt
    assert np.all(np.abs(steps) <= vel * 1.01 + 1e-9)
    accel = np.diff(steps, axis=0) / dt
    interior = np.abs(accel).max(axis=1)  # corners stop, so accelerations stay bounded
    assert np.percentile(interior, 99) <= acc.max() * 1.05
    led = time_parameterize(plan.waypoints, vel, acc, dt, lead=0.05)
    assert led.shape == traj.shape and np.allclose(led[-1], q_b)
    assert np.array_equal(time_parameterize(q_a[None], vel, acc, dt), q_a[None])
