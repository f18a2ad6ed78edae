"""The Panda holds a 0.3 kg box by finger friction alone while the servos lift it."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from poses import top_down

from utamp_gym.robot.collision import CollisionChecker
from utamp_gym.robot.kinematics import HOME_Q, PandaKinematics
from utamp_gym.robot.motion import (
    PANDA_ACC_LIMITS,
    PANDA_VEL_LIMITS,
    plan_motion,
    time_parameterize,
)
from utamp_gym.robot.panda_mjcf import (
    ARM_KP,
    ARM_KV,
    GRIPPER_FORCE,
    add_panda,
    apply_recommended_options,
    set_home,
)

pytestmark = pytest.mark.physics

TABLE_TOP = 0.3
HALF = 0.025  # 5 cm cube
DT = 0.002


def _build(recommended: bool):
    world = mujoco.MjSpec()
    if recommended:
        apply_recommended_options(world, DT)
    else:  # only what the arm strictly needs: implicit damping at 2 ms
        world.option.timestep = DT
        world.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    world.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    world.worldbody.add_geom(
        name="table",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.3, 0.4, TABLE_TOP / 2],
        pos=[0.55, 0, TABLE_TOP / 2],
    )
    body = world.worldbody.add_body(name="box", pos=[0.5, 0.05, TABLE_TOP + HALF])
    body.add_freejoint()
    body.add_geom(
        name="box_geom",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[HALF] * 3,
        mass=0.3,
        friction=[0.8, 0.005, 0.0001],
    )
    handles = add_panda(world)
    model = world.compile()
    return model, handles.bind(model)


@pytest.mark.parametrize("recommended", [True, False], ids=["elliptic", "default-cone"])
def test_gripper_lifts_box_by_friction(recommended):
    model, ids = _build(recommended)
    assert model.neq == 1 and model.eq_type[0] == mujoco.mjtEq.mjEQ_JOINT  # no weld anywhere
    data = mujoco.MjData(model)
    set_home(model, data, ids)
    box = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "box")
    kin = PandaKinematics()
    checker = CollisionChecker(model, ids)
    rng = np.random.default_rng(0)
    lead = ARM_KV[0] / ARM_KP[0]
    vel, acc = PANDA_VEL_LIMITS * 0.4, PANDA_ACC_LIMITS * 0.2

    def settle(steps: int) -> None:
        for _ in range(steps):
            mujoco.mj_step(model, data)

    def move_to(q_goal: np.ndarray, held: int | None = None) -> None:
        checker.sync(data)
        if held is not None:
            checker.attach(held)  # pose relative to the TCP taken from the current state
        q_now = data.qpos[ids.arm_qpos_adr].copy()
        plan = plan_motion(checker, q_now, q_goal, rng)
        for q in time_parameterize(plan.waypoints, vel, acc, DT, lead=lead):
            data.ctrl[ids.arm_actuator_ids] = q
            mujoco.mj_step(model, data)
        data.ctrl[ids.arm_actuator_ids] = q_goal
        settle(150)

    settle(100)
    centre = data.xpos[box].copy()
    q_pre = kin.ik(top_down(centre + np.array([0, 0, 0.12])), np.array(HOME_Q), rng).q
    q_grasp = kin.ik(top_down(centre), q_pre, rng).q
    q_lift = kin.ik(top_down(centre + np.array([0, 0, 0.15])), q_grasp, rng).q
    move_to(q_pre)
    move_to(q_grasp)
    np.testing.assert_allclose(data.site_xpos[ids.tcp_site_id], centre, atol=3e-3)
    data.ctrl[ids.gripper_actuator_id] = 0.0
    settle(300)
    gap = data.qpos[ids.finger_qpos_adr].sum()
    assert abs(gap - 2 * HALF) < 2e-3  # fingers stopped by the box, not through it
    assert data.actuator_force[ids.gripper_actuator_id] == pytest.approx(-GRIPPER_FORCE)
    offset0 = data.xpos[box] - data.site_xpos[ids.tcp_site_id]

    move_to(q_lift, held=box)
    settle(500)  # hold for another second
    rise = data.xpos[box][2] - centre[2]
    slip = np.linalg.norm(data.xpos[box] - data.site_xpos[ids.tcp_site_id] - offset0)
    assert rise > 0.14, f"box rose only {rise:.3f} m"
    assert slip < 3e-3, f"box slipped {slip * 1000:.1f} mm in the grasp"
    touching = {
        int(g)
        for c in data.contact[: data.ncon]
        for g in c.geom
        if box in (model.geom_bodyid[c.geom[0]], model.geom_bodyid[c.geom[1]])
    }
    table = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "table")
    assert set(ids.finger_pad_geom_ids) <= touching and table not in touching

    data.ctrl[ids.gripper_actuator_id] = 0.08  # release: the box falls back to the table
    settle(600)
    assert data.xpos[box][2] < centre[2] + 0.01
