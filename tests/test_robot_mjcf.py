"""MuJoCo Panda built from the URDF: structure, agreement with Pinocchio, servo behaviour."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from utamp_gym.robot.kinematics import HOME_Q, PandaKinematics
from utamp_gym.robot.panda_mjcf import (
    GRIPPER_FORCE,
    add_panda,
    apply_recommended_options,
    robot_geom_ids,
    set_home,
)

pytestmark = pytest.mark.physics

BASE = np.array([0.1, -0.2, 0.3])


@pytest.fixture(scope="module")
def panda():
    world = mujoco.MjSpec()
    apply_recommended_options(world)
    world.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    handles = add_panda(world, base_pos=BASE)
    model = world.compile()
    return handles, model, handles.bind(model)


def test_structure(panda):
    handles, model, ids = panda
    assert model.nu == 8 and len(ids.arm_actuator_ids) == 7
    assert model.neq == 1 and model.eq_type[0] == mujoco.mjtEq.mjEQ_JOINT  # fingers, no weld
    np.testing.assert_allclose(
        model.actuator_forcerange[ids.arm_actuator_ids, 1], [87] * 4 + [12] * 3
    )
    assert model.actuator_forcerange[ids.gripper_actuator_id, 1] == GRIPPER_FORCE
    assert model.nexclude > 0
    geoms = robot_geom_ids(model, handles.prefix)
    np.testing.assert_array_equal(geoms, ids.geom_ids)
    assert set(ids.finger_pad_geom_ids) <= set(ids.finger_geom_ids) <= set(geoms)
    assert model.geom_friction[ids.finger_pad_geom_ids[0], 0] >= 1.0
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, handles.hand_body) >= 0
    with pytest.raises(Exception, match="not in the model"):
        type(handles)(**{**handles.__dict__, "tcp_site": "nope"}).bind(model)


def test_pinocchio_and_mujoco_agree_on_tcp(panda):
    _, model, ids = panda
    kin = PandaKinematics()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = kin.random_q(rng)
        data.qpos[ids.arm_qpos_adr] = q
        mujoco.mj_kinematics(model, data)
        pose = kin.fk(q)
        np.testing.assert_allclose(data.site_xpos[ids.tcp_site_id], pose[:3, 3] + BASE, atol=1e-9)
        np.testing.assert_allclose(
            data.site_xmat[ids.tcp_site_id].reshape(3, 3), pose[:3, :3], atol=1e-9
        )


def test_home_is_collision_free_and_holds_still(panda):
    _, model, ids = panda
    data = mujoco.MjData(model)
    set_home(model, data, ids)
    assert data.ncon == 0
    for _ in range(500):
        mujoco.mj_step(model, data)
    assert np.abs(data.qpos[ids.arm_qpos_adr] - HOME_Q).max() < 1e-3
    assert np.isfinite(data.qacc).all()


def test_servo_reaches_setpoint_and_gripper_moves(panda):
    _, model, ids = panda
    data = mujoco.MjData(model)
    set_home(model, data, ids)
    goal = np.array(HOME_Q) + np.array([0.4, 0.2, -0.3, 0.3, 0.5, -0.3, 0.6])
    data.ctrl[ids.arm_actuator_ids] = goal
    data.ctrl[ids.gripper_actuator_id] = 0.02
    for _ in range(1000):  # 2 s, a step input (worst case for stability)
        mujoco.mj_step(model, data)
    assert np.abs(data.qpos[ids.arm_qpos_adr] - goal).max() < 2e-3
    fingers = data.qpos[ids.finger_qpos_adr]
    assert abs(fingers.sum() - 0.02) < 1e-3 and abs(fingers[0] - fingers[1]) < 1e-4
    assert np.abs(data.qvel).max() < 1e-2
