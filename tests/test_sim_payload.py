"""Payload from joint torques: the arm's gravity compensation counts against its torque
limits, the load on the hand is estimated from the joint torques, and overload fails a
pick with a reason that names the object and the measured load.

Physics tests look only at what the simulation measured (torques, poses, finger gap);
the catalogue mass is what the test sets up, never what the skill reads.
"""

from __future__ import annotations

import re
from typing import Any

import mujoco
import numpy as np
import pytest

from utamp_gym.robot.kinematics import PandaKinematics
from utamp_gym.robot.panda_mjcf import add_panda, apply_recommended_options, set_home
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.sim.control import ArmDriver
from utamp_gym.sim.payload import RATED_PAYLOAD_KG, hold_and_measure, payload_failure

physics = pytest.mark.physics
PICK_WEIGHT = "(pick-support weight weight-body on left right back on slot1 under on)"
PLACE_WEIGHT = "(place-support weight weight-body on left right back on under slot2 under on)"


# ------------------------------------------------------------------ a Panda holding a mass
@pytest.fixture(scope="module")
def kin() -> PandaKinematics:
    return PandaKinematics()


def _panda_holding(
    kin: PandaKinematics, mass: float, offset: tuple[float, float, float]
) -> ArmDriver:
    """A Panda at its ready pose with a `mass` kg box fixed to the hand at `offset` (m,
    TCP frame). The box has no gravity compensation: its weight is a load on the joints."""
    world = mujoco.MjSpec()
    apply_recommended_options(world)
    handles = add_panda(world)
    world.body(handles.tcp_body).add_body(name="load", pos=list(offset)).add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.02, 0.02, 0.02],
        mass=mass,
        contype=0,
        conaffinity=0,
    )
    model = world.compile()
    data = mujoco.MjData(model)
    ids = handles.bind(model)
    set_home(model, data, ids)
    arm = ArmDriver(model, data, ids, kin, np.random.default_rng(0))
    arm.step(round(0.6 / arm.dt))  # let the servos take up the load
    return arm


def test_arm_gravity_compensation_goes_through_the_torque_limited_actuators(kin):
    arm = _panda_holding(kin, 1e-6, (0.0, 0.0, 0.0))
    m, d, ids = arm.model, arm.data, arm.ids
    assert m.jnt_actgravcomp[ids.arm_joint_ids].all()
    assert m.jnt_actfrclimited[ids.arm_joint_ids].all()
    np.testing.assert_allclose(m.jnt_actfrcrange[ids.arm_joint_ids, 1], [87] * 4 + [12] * 3)
    # the compensation is actuator torque (clamped with it), not a passive force
    gravity = d.qfrc_gravcomp[ids.arm_dof_adr]
    assert np.abs(gravity).max() > 5.0
    np.testing.assert_allclose(d.qfrc_actuator[ids.arm_dof_adr], gravity, atol=0.05)
    assert np.abs(d.qfrc_passive[ids.arm_dof_adr]).max() < 0.05
    assert np.abs(arm.q() - d.ctrl[ids.arm_actuator_ids]).max() < 1e-4  # holds its pose


@pytest.mark.parametrize(
    ("mass", "offset"), [(0.5, (0.0, 0.0, 0.05)), (2.0, (0.06, 0.02, 0.03)), (2.9, (0, 0, 0))]
)
def test_load_estimate_of_a_hanging_mass(kin, mass, offset):
    arm = _panda_holding(kin, mass, offset)
    reading = hold_and_measure(arm)
    assert reading.mass_kg == pytest.approx(mass, rel=0.03)
    assert np.linalg.norm(reading.force[:2]) < 0.05 * mass * 9.81  # it pulls straight down
    # the lever of its weight: the offset's horizontal part, in the world (hand points down)
    horizontal = np.linalg.norm((arm.tcp()[:3, :3] @ np.asarray(offset))[:2])
    assert reading.lever_m == pytest.approx(horizontal, abs=0.005)
    assert not reading.saturated and not reading.overloaded
    assert payload_failure("box", reading, while_="lifting") is None


def test_empty_hand_reads_no_load(kin):
    reading = hold_and_measure(_panda_holding(kin, 1e-6, (0.0, 0.0, 0.0)))
    assert reading.mass_kg < 0.02 and not reading.overloaded


def test_a_mass_over_the_payload_and_one_the_wrist_cannot_hold(kin):
    heavy = hold_and_measure(_panda_holding(kin, 4.0, (0.0, 0.0, 0.0)))
    assert heavy.mass_kg == pytest.approx(4.0, rel=0.03) and heavy.overloaded
    reason = payload_failure("box", heavy, while_="lifting")
    assert reason is not None and "payload" in reason and "box" in reason and "4.0 kg" in reason
    # 2.5 kg is within the payload, but 45 cm out from the hand it needs > 12 N·m at the wrist
    far = hold_and_measure(_panda_holding(kin, 2.5, (0.45, 0.0, 0.0)))
    assert far.saturated == (6,)  # the wrist sags: the arm cannot hold the pose
    reason = payload_failure("box", far, while_="carrying")
    assert reason is not None and "payload" in reason and "N·m limit" in reason


# ------------------------------------------------------------------ picks in physics
def _weight_scene(mass: float) -> Any:
    """A compact 6 x 6 x 10 cm block of `mass` kg, grasped across its body from above."""
    sides = {s: {"shape": "flat"} for s in ("on", "under", "left", "right", "front", "back")}
    block = {
        "mass": mass, "material": "metal", "robustness": "solid", "parts": sides,
        "members": {"body": {"min": [-0.03, -0.03, 0.0], "max": [0.03, 0.03, 0.10]}},
    }  # fmt: skip
    return scene_from_dict({
        "name": f"weight-{mass}", "types": {"weight": block},
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "slots": [
            {"name": "slot1", "position": [0.5, 0.0], "min": [0.3, -0.2], "max": [0.7, 0.2]},
            {"name": "slot2", "position": [0.5, 0.35], "min": [0.3, 0.2], "max": [0.7, 0.5]},
        ],
        "objects": [{"name": "weight", "type": "weight", "on": "slot1"}],
    })  # fmt: skip


@pytest.fixture
def backend():
    from utamp_gym.sim.backend import MujocoBackend

    sim = MujocoBackend()
    yield sim
    sim.close()


def _support(sim, name: str) -> str | None:
    from utamp_gym.sim.world import stack_from_poses

    return stack_from_poses(sim.state.world, sim.state.data)[name]


@physics
def test_the_same_grasp_lifts_2_kg_and_refuses_5_kg(backend):
    backend.reset(_weight_scene(2.0), np.random.default_rng(0))
    picked = backend.execute(PICK_WEIGHT)
    assert picked.success, picked.reason
    assert hold_and_measure(backend.state.arm).mass_kg == pytest.approx(2.0, rel=0.1)
    placed = backend.execute(PLACE_WEIGHT)
    assert placed.success, placed.reason
    assert _support(backend, "weight") == "slot2"

    backend.reset(_weight_scene(5.0), np.random.default_rng(0))
    res = backend.execute(PICK_WEIGHT)
    assert not res.success
    assert "weight" in res.reason and "payload" in res.reason
    measured = float(re.search(r"measure (\d+\.\d) kg", res.reason).group(1))
    assert measured == pytest.approx(5.0, rel=0.1) and measured > RATED_PAYLOAD_KG
    assert backend.state.held is None  # it let go: the block is back on its slot
    assert _support(backend, "weight") == "slot1"


@physics
@pytest.mark.parametrize(
    "grasp", ["tray-handle-back on front back", "tray-edge-right on left right"]
)
def test_the_tray_cannot_be_lifted(backend, demo_dict, grasp):
    backend.reset(scene_from_dict(demo_dict), np.random.default_rng(0))
    res = backend.execute(f"(pick-support tray {grasp} back on slot1 under on)")
    assert not res.success
    # a physical reason with the load the joints measured: over the payload, or the grasp
    # cannot hold the tray's moment and it turns in the fingers (its far edge on the table)
    assert res.reason.startswith("tray ") and " kg (" in res.reason
    assert "payload" in res.reason or "not liftable" in res.reason
    assert backend.state.held is None and _support(backend, "tray") == "slot1"
