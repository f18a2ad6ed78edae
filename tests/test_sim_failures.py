"""Failure detection in physics: a dropped object and a toppled stack are reported.

Both failures are produced physically (a force on the held object, a knock on the
base of a stack) and detected only from the simulated poses, velocities and finger
gap, as during an episode.
"""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.resources import asset_path
from utamp_gym.scene.io import load_scene

physics = pytest.mark.physics

PICK_SALT = "(pick-support salt salt-body on left right back on slot5 under on)"
PLACE_SALT_ON_MUG = "(place-support salt salt-body on left right back on under mug back under)"
PLACE_SALT_ON_TRAY = "(place-support salt salt-body on left right back on under tray back on)"


@pytest.fixture(scope="module")
def demo():
    return load_scene(asset_path("scenes", "kitchen-demo.toml"))


@pytest.fixture
def backend():
    from utamp_gym.sim.backend import MujocoBackend

    sim = MujocoBackend()
    yield sim
    sim.close()


@physics
def test_an_object_pulled_out_of_the_hand_is_reported_dropped(backend, demo):
    backend.reset(demo, np.random.default_rng(0))
    assert backend.execute(PICK_SALT).success
    st = backend.state
    salt = st.world.body_ids["salt"]
    # a 40 kg-weight pull: more than the pads' friction can hold (2 pads x mu 1.5 x ~70 N)
    st.data.xfrc_applied[salt, 2] = -400.0
    res = backend.execute(PLACE_SALT_ON_TRAY)
    st.data.xfrc_applied[salt] = 0.0
    assert not res.success
    assert "salt dropped during transport" in res.reason
    assert st.held is None  # the hand does not pretend to hold it
    gap = np.linalg.norm(st.arm.tcp()[:3, 3] - st.data.xpos[salt])
    assert gap > 0.05  # and the shaker really left it


@physics
def test_a_knocked_over_stack_is_detected(backend, demo):
    from utamp_gym.sim.measure import SkillFailure, disturbed, settle_objects, snapshot, verify_on
    from utamp_gym.sim.world import stack_from_poses

    backend.reset(demo, np.random.default_rng(0))
    assert backend.execute(PICK_SALT).success
    placed = backend.execute(PLACE_SALT_ON_MUG)
    assert placed.success, placed.reason
    st = backend.state
    assert stack_from_poses(st.world, st.data)["salt"] == "mug"
    before = snapshot(st, set())
    verify_on(st, "salt", "mug")  # standing: no failure
    assert disturbed(st, before) is None
    # knock the mug sideways (1.5 m/s): the shaker on it falls
    mug = st.world.dof_adr["mug"]
    st.data.qvel[mug : mug + 3] = [0.0, -1.5, 0.0]
    settle_objects(st, min_s=1.0, max_s=3.0)
    moved = disturbed(st, before)
    assert moved is not None and ("mug" in moved or "salt" in moved)
    with pytest.raises(SkillFailure, match=r"salt (fell off|tipped over on) mug"):
        verify_on(st, "salt", "mug")
