"""Sleeping islands (`build_world_spec(sleep=True)`, the macro-action backend's world).

Objects at rest are frozen and skipped by collision detection until something awake
touches them. These tests check that this changes what physics decides nowhere: unstable
stacks still fall, stable ones keep their supports (measured on the live data, whose
sleeping contacts are not computed), a sleeping object touched by the robot wakes and is
picked, and the planner's collision model still sees every object.
"""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.sim.backend import MujocoBackend
from utamp_gym.sim.world import (
    build_world_spec,
    compile_world,
    object_pose,
    rests_on_top,
    settle,
    sleeping_objects,
    stack_from_poses,
)
from utamp_gym.suites import resolve_scene

pytestmark = pytest.mark.physics

WORKSPACE = {"min": [0.0, -0.6, 0.0], "max": [0.8, 0.6, 0.7]}


def tower(*stack: tuple[str, str]):
    """One stack in one big slot: (type, orientation) from the bottom up."""
    objects, below = [], "slot1"
    for i, (kind, orientation) in enumerate(stack):
        objects.append({"name": f"o{i}", "type": kind, "on": below, "orientation": orientation})
        below = f"o{i}"
    return scene_from_dict(
        {
            "name": "test-tower",
            "workspace": WORKSPACE,
            "slots": [
                {"name": "slot1", "position": [0.5, 0.0], "min": [0.1, -0.4], "max": [0.9, 0.4]}
            ],
            "objects": objects,
        }
    )


def run(scene, sleep: bool, seconds: float = 2.0):
    spec, info = build_world_spec(scene, rng=np.random.default_rng(1), sleep=sleep)
    world = compile_world(spec, info)
    data = world.make_data()
    start = {n: object_pose(world.model, data, n)[0] for n in world.body_ids}
    settle(world.model, data, seconds)
    return world, data, start


@pytest.mark.parametrize(
    "stack",
    [
        (("salt-shaker", "upright"), ("glass-mug", "upright")),  # the mug falls off
        (("glass-mug", "upright"), ("salt-shaker", "upright")),  # the shaker drops in
    ],
)
def test_unstable_stacks_still_fall(stack):
    world, data, start = run(tower(*stack), sleep=True)
    assert object_pose(world.model, data, "o1")[0][2] < start["o1"][2] - 0.03
    assert not rests_on_top(world, data, "o1", "o0")


@pytest.mark.parametrize(
    "stack",
    [
        (("frying-pan", "upright"), ("cutting-board", "upright"), ("glass-mug", "inverted")),
        (("glass-mug", "inverted"), ("salt-shaker", "upright")),
    ],
)
def test_stable_stacks_sleep_in_place_and_keep_their_supports(stack):
    world, data, _ = run(tower(*stack), sleep=True)
    awake_world, awake_data, _ = run(tower(*stack), sleep=False)
    assert sleeping_objects(world, data) == set(world.body_ids)
    expected = {f"o{i}": "slot1" if i == 0 else f"o{i - 1}" for i in range(len(stack))}
    assert stack_from_poses(world, data) == expected  # the live data, no scratch
    for name in world.body_ids:
        a = object_pose(world.model, data, name)[0]
        b = object_pose(awake_world.model, awake_data, name)[0]
        assert np.linalg.norm(a - b) < 1e-3, name


def test_the_robot_wakes_and_picks_a_sleeping_object():
    scene = resolve_scene("pick-place/000")
    pick = plan_scene(scene, "utamp2-gt").plan[0]
    name = pick.strip("()").split()[1]
    sim = MujocoBackend(pose_noise=0.0)
    sim.reset(scene, np.random.default_rng(0))
    st = sim.state
    settle(st.world.model, st.data, 0.2)
    assert sleeping_objects(st.world, st.data) == set(st.world.body_ids)
    # the planner's collision model sees sleeping objects: one moved into the hand collides
    checker = st.arm.sync(st.arm.near)
    adr = st.world.qpos_adr[name]
    checker.data.qpos[adr : adr + 3] = st.arm.tcp()[:3, 3]
    touched = {g for c in checker.contacts(st.arm.q(), tolerate=False) for g in (c.geom1, c.geom2)}
    assert touched & set(st.world.geom_ids[name])
    z = object_pose(st.world.model, st.data, name)[0][2]
    result = sim.execute(pick)
    assert result.success, result.reason
    assert name not in sleeping_objects(st.world, st.data)
    assert object_pose(st.world.model, st.data, name)[0][2] > z + 0.1
    sim.close()
