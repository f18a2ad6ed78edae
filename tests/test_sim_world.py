"""The MuJoCo world built from scenes: structure, seeded noise, stability and affordances.

Physics, not hard-coded outcomes, must reproduce the paper's affordances: these tests
drop objects on each other and only look at the simulated poses and contacts.
"""

from __future__ import annotations

import time
from typing import Any

import mujoco
import numpy as np
import pytest

from utamp_gym.errors import SimulationError, UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import load_catalogue
from utamp_gym.scene.io import load_scene, scene_from_dict
from utamp_gym.sim.bodies import object_prims
from utamp_gym.sim.world import (
    build_world,
    build_world_spec,
    compile_world,
    object_orientation,
    object_pose,
    object_velocity,
    rests_on_top,
    settle,
    stack_from_poses,
)
from utamp_gym.suites.generate import get_scene, suite_scenes

pytestmark = pytest.mark.physics

WORKSPACE = {"min": [0.0, -0.6, 0.0], "max": [0.8, 0.6, 0.7]}
SUBSET = ("pick-place/000", "pick-place/040", "pick-place/103", "pick-place/104",
          "pick-place/105", "sliding/041")  # fmt: skip


@pytest.fixture(scope="module")
def demo():
    return load_scene(asset_path("scenes", "kitchen-demo.toml"))


def tower(*stack: tuple[str, str], types: dict[str, Any] | None = None):
    """A scene with one stack in one big slot: (type, orientation) from the bottom up."""
    objects, below = [], "slot1"
    for i, (kind, orientation) in enumerate(stack):
        objects.append({"name": f"o{i}", "type": kind, "on": below, "orientation": orientation})
        below = f"o{i}"
    data = {
        "name": "test-tower",
        "workspace": WORKSPACE,
        "slots": [{"name": "slot1", "position": [0.5, 0.0], "min": [0.1, -0.4], "max": [0.9, 0.4]}],
        "objects": objects,
    }
    if types:
        data["types"] = types
    return scene_from_dict(data)


def run(scene, seconds: float = 2.0, seed: int | None = None):
    world = build_world(scene, rng=None if seed is None else np.random.default_rng(seed))
    data = world.make_data()
    start = {n: object_pose(world.model, data, n)[0] for n in world.body_ids}
    settle(world.model, data, seconds)
    return world, data, start


def max_displacement(world, data, start) -> float:
    now = {n: object_pose(world.model, data, n)[0] for n in start}
    return max(float(np.linalg.norm(now[n] - p)) for n, p in start.items())


# ------------------------------------------------------------------------- structure
def test_structure_matches_scene(demo):
    world = build_world(demo)
    m = world.model
    assert set(world.body_ids) == set(demo.object_names)
    for name, body in world.body_ids.items():
        assert m.body_mass[body] == pytest.approx(demo.type_of(name).mass)
        assert m.body_jntnum[body] == 1
        assert m.jnt_type[m.body_jntadr[body]] == mujoco.mjtJoint.mjJNT_FREE
        assert all(m.geom_bodyid[g] == body for g in world.geom_ids[name])
        a = world.qpos_adr[name]
        pose = demo.poses[name]
        np.testing.assert_allclose(m.qpos0[a : a + 7], [*pose.position, *pose.quat], atol=1e-12)
        assert world.object_of_geom(world.geom_ids[name][0]) == name
    assert m.body_mass[world.body_ids["tray"]] > 3.0  # beyond the Panda's payload
    assert set(world.slot_positions) == {s.name for s in demo.slots}
    np.testing.assert_allclose(world.slot_positions["slot2"], [0.22, 0.38, 0.0])
    table = m.geom(world.table_geom_id)
    np.testing.assert_allclose(table.pos + table.size, [1.3, 0.9, 0.0])  # top at z = 0
    assert world.object_of_geom(world.table_geom_id) is None
    assert m.opt.timestep == 0.002
    with pytest.raises(UnknownNameError, match="valid: board"):
        object_pose(m, world.make_data(), "plate")
    with pytest.raises(SimulationError):
        build_world(demo, timestep=0.0)


def _aabb(p) -> tuple[np.ndarray, np.ndarray]:
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(p.quat))
    half = np.asarray(p.size)
    if p.shape == "cylinder":
        half = np.array([p.size[0], p.size[0], p.size[1]])
    ext = np.abs(rot.reshape(3, 3)) @ half
    return np.asarray(p.pos) - ext, np.asarray(p.pos) + ext


@pytest.mark.parametrize("kind", sorted(load_catalogue().types))
def test_primitives_stay_inside_the_catalogue_box(kind):
    t = load_catalogue()[kind]
    for p in object_prims(t):
        lo, hi = _aabb(p)
        assert np.all(lo >= np.asarray(t.bbox.min) - 1e-4), (p.name, lo)
        assert np.all(hi <= np.asarray(t.bbox.max) + 1e-4), (p.name, hi)


def test_shapes_follow_the_parts():
    cat = load_catalogue()
    prims = {k: {p.name: p for p in object_prims(cat[k])} for k in cat.types}
    assert prims["salt-shaker"]["body/head"].shape == "ellipsoid"  # rounded head
    mug = prims["glass-mug"]
    assert "body/floor" in mug and sum("wall" in n for n in mug) >= 8  # hollow, open top
    assert {"handle/top", "handle/bottom", "handle/grip"} <= set(mug)  # a loop
    pan = prims["frying-pan"]
    assert pan["body/floor"].size[0] == pytest.approx(0.08)  # the `under` part's size
    tray = prims["wooden-tray"]
    bar, post = tray["handle-front"], tray["handle-front/post0"]
    gap = bar.pos[0] - bar.size[0] - 0.175  # between the tray's front wall and the bar
    assert gap >= 0.025 and post.size[0] * 2 == pytest.approx(gap)  # fingers fit in the gap
    assert not any(n.startswith("edge") for n in tray)  # edges are the rim itself


def test_a_robot_can_be_attached_before_compiling(demo):
    spec, info = build_world_spec(demo)
    arm = mujoco.MjSpec()
    link = arm.worldbody.add_body(name="link")
    link.add_joint(name="j", type=mujoco.mjtJoint.mjJNT_HINGE)
    link.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.03, 0.1, 0], pos=[0, 0, 0.3])
    spec.attach(arm, prefix="robot/", frame=spec.worldbody.add_frame(pos=[0, 0, 0]))
    world = compile_world(spec, info)
    assert world.model.nq == 1 + 7 * len(demo.objects)
    data = world.make_data()
    for name, pose in info.poses.items():
        np.testing.assert_allclose(object_pose(world.model, data, name)[0], pose.position)


def test_the_panda_stands_on_the_table_without_disturbing_the_scene(demo):
    from utamp_gym.robot import panda_mjcf as panda

    spec, info = build_world_spec(demo, rng=np.random.default_rng(0))
    handles = panda.add_panda(spec)
    world = compile_world(spec, info)
    data = mujoco.MjData(world.model)
    panda.set_home(world.model, data, handles.bind(world.model))
    start = {n: object_pose(world.model, data, n)[0] for n in world.body_ids}
    settle(world.model, data, 0.5)
    assert max_displacement(world, data, start) < 0.002
    assert stack_from_poses(world, data) == {o.name: o.on for o in demo.objects}


# ------------------------------------------------------------------------- noise
def test_seeded_noise(demo):
    a = build_world(demo, rng=np.random.default_rng(7)).model.qpos0
    b = build_world(demo, rng=np.random.default_rng(7)).model.qpos0
    c = build_world(demo, rng=np.random.default_rng(8)).model.qpos0
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    world = build_world(demo)
    np.testing.assert_array_equal(world.initial_qpos(np.random.default_rng(7)), a)
    for name in demo.object_names:
        adr = world.qpos_adr[name]
        nominal = world.model.qpos0[adr : adr + 7]
        assert np.all(np.abs(a[adr : adr + 2] - nominal[:2]) <= 0.003)
        assert a[adr + 2] == nominal[2]
        dot = abs(float(np.dot(a[adr + 3 : adr + 7], nominal[3:])))
        assert np.degrees(2 * np.arccos(min(dot, 1.0))) <= 2.0 + 1e-9
    zero = build_world(demo, rng=np.random.default_rng(7), pos_noise=0, yaw_noise_deg=0)
    np.testing.assert_allclose(zero.model.qpos0, world.model.qpos0, atol=1e-12)


# ------------------------------------------------------------------------- stability
def _assert_stays_put(scene):
    world, data, start = run(scene, 2.0, seed=0)
    assert max_displacement(world, data, start) < 0.005, scene.description
    stack = stack_from_poses(world, data)
    for o in scene.objects:
        assert stack[o.name] == o.on, (scene.name, o.name)
        assert object_orientation(world.model, data, o.name) == o.orientation
        assert rests_on_top(world, data, o.name, stack[o.name])


@pytest.mark.parametrize("name", SUBSET)
def test_suite_scenes_stay_put(name):
    _assert_stays_put(get_scene(name))


@pytest.mark.slow
@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_every_suite_scene_stays_put(suite):
    for scene in suite_scenes(suite):
        _assert_stays_put(scene)


def test_stack_from_poses_on_the_demo(demo):
    world, data, _ = run(demo, 1.0, seed=3)
    assert stack_from_poses(world, data) == {o.name: o.on for o in demo.objects}
    lin, ang = object_velocity(world.model, data, "tray")
    assert np.linalg.norm(lin) < 1e-3 and np.linalg.norm(ang) < 1e-2
    a = world.qpos_adr["salt"]  # lift the shaker into the air: nothing supports it
    data.qpos[a + 2] += 0.3
    before = data.xpos.copy()
    assert stack_from_poses(world, data)["salt"] is None
    np.testing.assert_array_equal(data.xpos, before)  # the caller's data is left alone
    data.qpos[a : a + 3] = [-0.2, 0.6, 0.0]  # on the table, outside every slot
    assert stack_from_poses(world, data)["salt"] == "table"


# ------------------------------------------------------------------------- affordances
@pytest.mark.parametrize("seed", [None, 1])
def test_upright_mug_falls_off_the_shaker(seed):
    world, data, start = run(tower(("salt-shaker", "upright"), ("glass-mug", "upright")), seed=seed)
    assert stack_from_poses(world, data)["o1"] != "o0"
    assert not rests_on_top(world, data, "o1", "o0")
    assert object_pose(world.model, data, "o1")[0][2] < start["o1"][2] - 0.03


@pytest.mark.parametrize("seed", [None, 1])
def test_shaker_does_not_stay_on_the_open_top(seed):
    world, data, start = run(tower(("glass-mug", "upright"), ("salt-shaker", "upright")), seed=seed)
    assert object_pose(world.model, data, "o1")[0][2] < start["o1"][2] - 0.03
    assert not rests_on_top(world, data, "o1", "o0")


@pytest.mark.parametrize("seed", [None, 1])
def test_shaker_stands_on_the_inverted_mug(seed):
    scene = tower(("glass-mug", "inverted"), ("salt-shaker", "upright"))
    world, data, start = run(scene, seed=seed)
    assert max_displacement(world, data, start) < 0.002
    assert stack_from_poses(world, data) == {"o0": "slot1", "o1": "o0"}
    assert rests_on_top(world, data, "o1", "o0")


@pytest.mark.parametrize("seed", [None, 1])
def test_board_rests_across_the_pan(seed):
    scene = tower(("frying-pan", "upright"), ("cutting-board", "upright"))
    world, data, start = run(scene, seed=seed)
    assert max_displacement(world, data, start) < 0.002
    assert stack_from_poses(world, data)["o1"] == "o0"
    assert rests_on_top(world, data, "o1", "o0")


def test_custom_types_get_generic_bodies():
    parts = {s: {"shape": "flat"} for s in ("on", "under", "left", "right", "front", "back")}
    types = {
        "block": {"mass": 1.5, "material": "plastic", "robustness": "sturdy",
                  "members": {"body": {"min": [-0.1, -0.08, 0], "max": [0.1, 0.08, 0.12]},
                              "handle": {"kind": "handle", "min": [-0.14, -0.03, 0.08],
                                         "max": [-0.1, 0.03, 0.1]}},
                  "parts": parts},
        "bowl": {"mass": 0.4, "material": "ceramic", "robustness": "fragile",
                 "members": {"body": {"geom": "cylinder", "min": [-0.07, -0.07, 0],
                                      "max": [0.07, 0.07, 0.06]}},
                 "parts": {**parts, "on": {"shape": "concave", "size": [0.14, 0.14]},
                           "under": {"shape": "flat", "size": [0.08, 0.08]}}},
        "crate": {"mass": 0.8, "material": "wood", "robustness": "sturdy",
                  "members": {"body": {"min": [-0.1, -0.08, 0], "max": [0.1, 0.08, 0.1]}},
                  "parts": {**parts, "on": {"shape": "open"}}},
    }  # fmt: skip
    scene = tower(("block", "upright"), ("bowl", "upright"), ("crate", "upright"), types=types)
    world, data, start = run(scene, 1.0, seed=2)
    assert world.model.body_mass[world.body_ids["o0"]] == pytest.approx(1.5)
    assert [len(world.geom_ids[n]) for n in ("o0", "o1", "o2")] == [2, 13, 5]
    assert max_displacement(world, data, start) < 0.005
    assert stack_from_poses(world, data) == {"o0": "slot1", "o1": "o0", "o2": "o1"}


# ------------------------------------------------------------------------- speed
def test_demo_world_step_rate(demo, record_property):
    """Records the step rate (speed targets live in benchmarks/, not in timed tests: machines
    are shared); asserts that the resting scene steps stably."""
    world = build_world(demo, rng=np.random.default_rng(0))
    data = world.make_data()
    settle(world.model, data, 0.2)
    before = data.qpos.copy()
    n, best = 1000, 0.0
    for _ in range(3):
        t0 = time.perf_counter()
        mujoco.mj_step(world.model, data, nstep=n)
        best = max(best, n / (time.perf_counter() - t0))
    record_property("mj_step_per_s", round(best))
    print(f"demo world (5 objects, no robot): {best:.0f} mj_step/s, ncon {data.ncon}")
    assert data.time == pytest.approx((3 * n + round(0.2 / world.model.opt.timestep)) * 0.002)
    assert np.abs(data.qpos - before).max() < 0.01  # 6 s later everything still rests
