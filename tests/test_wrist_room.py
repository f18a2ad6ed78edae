"""The wrist above the hand in the extended domain's grasp rules (`hand.wrist_blocker`):
its size is the Panda's link-7 collision mesh, an upside-down stock pot's lug near the
table is refused because the wrist lands on the pot's floor, and physics agrees (the hand
stopped 11 mm short on procedural-v2/test-tasks/0005 before the rule)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from utamp_gym.affordances.hand import WRIST_ABOVE_TCP, WRIST_HALF_WIDTH, WRIST_REACH
from utamp_gym.affordances.rules import _fingers_refusal, object_facts
from utamp_gym.kitchenware import generate
from utamp_gym.robot.panda_mjcf import add_panda

POT = ("stock-pot", "v1", 3461910483)  # procedural-v2/test-tasks/0005's obj1


def _link7_in_tcp_frame() -> np.ndarray:
    """The vertices of the simulated Panda's link-7 collision mesh in the TCP frame."""
    world = mujoco.MjSpec()
    handles = add_panda(world)
    model = world.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, handles.tcp_site)
    rot, pos = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "panda/panda_link7_collision0")
    assert g >= 0
    mesh = model.geom_dataid[g]
    adr, n = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    verts = model.mesh_vert[adr : adr + n] @ data.geom_xmat[g].reshape(3, 3).T
    return (verts + data.geom_xpos[g] - pos) @ rot


def test_the_wrist_constants_are_the_panda_link7_collision_mesh():
    v = _link7_in_tcp_frame()  # TCP frame: z along the approach, y along the fingers' axis
    assert -v[:, 2].max() == pytest.approx(WRIST_ABOVE_TCP, abs=5e-4)
    assert np.abs(v[:, 0]).max() == pytest.approx(WRIST_HALF_WIDTH, abs=5e-4)
    assert np.abs(v[:, 1]).max() == pytest.approx(WRIST_REACH, abs=5e-4)


def test_an_upside_down_pot_by_a_lug_is_refused_for_the_wrist_in_the_extended_domain_only():
    t = generate(*POT)
    refusal = _fingers_refusal(t, "handle-left", "under", "front", "back", True, True)
    assert refusal is not None and refusal.rule == "wrist-room"
    assert refusal.values["other"] == t.body.name
    assert "wrist" in refusal.detail
    grasp = ("canGraspFrom", t.name, "handle-left", "under", "front", "back")
    assert grasp not in object_facts(t, extended=True)
    assert grasp in object_facts(t, extended=False)  # the paper's rules are unchanged
    # upright, the lug is at the pot's top: the wrist is far above everything
    upright = ("canGraspFrom", t.name, "handle-left", "on", "front", "back")
    assert _fingers_refusal(t, "handle-left", "on", "front", "back", True, True) is None
    assert upright in object_facts(t, extended=True)


@pytest.mark.physics
def test_physics_agrees_the_wrist_lands_on_the_upside_down_pot():
    from utamp_gym.sim.backend import MujocoBackend
    from utamp_gym.suites import resolve_scene

    scene = resolve_scene("procedural-v2/test-tasks/0005")
    assert scene.type_of("obj1").name == generate(*POT).name
    sim = MujocoBackend()
    try:
        sim.reset(scene, np.random.default_rng(0))
        res = sim.execute(
            "(pick-support obj1 obj1-handle-left under front back back under slot5 on on)"
        )
    finally:
        sim.close()
    assert not res.success and "stopped short" in res.reason
