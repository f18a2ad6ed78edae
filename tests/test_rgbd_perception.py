"""Perception from rendered RGB-D: cameras, attributes, poses, `utamp2-perceived`.

Tolerances stated here are the contract of `utamp_gym.perception` on the paper's objects:
body sizes within `SIZE_TOL`, poses within `POSE_TOL` (position) and `YAW_TOL_DEG`, part
shapes exact. Rendering is headless (MuJoCo's EGL or OSMesa backend).
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

import utamp_gym
from utamp_gym.contract.views import BACKGROUND, ROBOT, ViewBundle
from utamp_gym.errors import UnknownNameError
from utamp_gym.perception.objects import perceive_objects
from utamp_gym.robot.panda_mjcf import add_panda, set_home
from utamp_gym.scene.catalogue import Catalogue
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.sim.cameras import (
    ACTING_SIZE,
    ACTING_VIEWS,
    SURVEY_SIZE,
    SURVEY_VIEWS,
    WRIST,
    CameraRig,
    add_wrist_camera,
)
from utamp_gym.sim.gl import new_renderer
from utamp_gym.sim.offscreen import Offscreen
from utamp_gym.sim.world import build_world_spec, compile_world

pytestmark = pytest.mark.physics

SIZE_TOL = 0.005  # m, body extents
POSE_TOL = 0.004  # m, body centre
YAW_TOL_DEG = 3.0
HANDLE_TOL = 0.015  # m, a handle's centre
BAR_TOL = 0.002  # m, the thickness of a tray's handle bar


def _world(data: dict, *, yaw: dict[str, float] | None = None, seed: int = 0):
    scene = scene_from_dict(data)
    spec, info = build_world_spec(
        scene, rng=np.random.default_rng(seed), pos_noise=0.0, yaw_noise_deg=0.0
    )
    for name, angle in (yaw or {}).items():
        body = spec.body(f"obj/{name}")
        body.quat = [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]
    handles = add_panda(spec)
    add_wrist_camera(spec, handles.prefix)
    world = compile_world(spec, info)
    data_ = mujoco.MjData(world.model)
    ids = handles.bind(world.model)
    set_home(world.model, data_, ids)
    mujoco.mj_forward(world.model, data_)
    rig = CameraRig(world.model, world.body_ids, ids.body_ids)
    return scene, world, data_, rig


@pytest.fixture(scope="module")
def single():
    """The cutting board and the glass mug (upright), apart, at known poses."""
    data = {
        "name": "perception-single",
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "table": {"type": "kitchen-table"},
        "slots": [
            {"name": "slot1", "position": [0.55, -0.1], "min": [0.3, -0.3], "max": [0.8, 0.1]},
            {"name": "slot2", "position": [0.45, 0.3], "min": [0.3, 0.15], "max": [0.6, 0.45]},
        ],
        "objects": [
            {"name": "board", "type": "cutting-board", "on": "slot1"},
            {"name": "mug", "type": "glass-mug", "on": "slot2"},
        ],
        "goal_base": "board",
    }
    scene, world, d, rig = _world(data)
    bundle = rig.look(d, SURVEY_VIEWS, SURVEY_SIZE)
    yield scene, world, d, rig, bundle
    rig.close()


def test_cameras_render_depth_and_object_level_masks_headless(single):
    _, world, _, _, bundle = single
    assert [v.camera for v in bundle.views] == list(SURVEY_VIEWS)
    for v in bundle.views:
        assert v.rgb is not None and v.rgb.shape == (SURVEY_SIZE[1], SURVEY_SIZE[0], 3)
        assert v.depth.shape == v.instances.shape == (SURVEY_SIZE[1], SURVEY_SIZE[0])
        # one id per object, never per geom or member: the ids are the instances 1..N
        ids = set(np.unique(v.instances).tolist())
        assert ids <= {BACKGROUND, ROBOT, 1, 2}
        # metric depth: the table seen is at z = 0 in the world
        table = v.points((v.instances == BACKGROUND) & (v.depth < 3.0))
        on_table = np.all(np.abs(table[:, :2] - [0.5, 0.0]) < [0.7, 0.8], axis=1)
        near = table[on_table & (np.abs(table[:, 2]) < 0.05)]
        assert len(near) > 100 and np.abs(near[:, 2]).max() < 1e-4
    seen = bundle.instance_ids()
    assert seen == [1, 2]
    # the mug's handle and body share one id: its geoms all map to instance 2
    mug_geoms = world.geom_ids["mug"]
    assert len(mug_geoms) > 3


def test_one_pass_gives_mujocos_depth_masks_and_colour_pixel_for_pixel(single):
    """`Offscreen` reads depth and segments from one pass; the images equal those of
    `mujoco.Renderer`'s separate depth, segmentation and colour passes."""
    _, world, d, _, _ = single
    w, h = ACTING_SIZE
    off = Offscreen(world.model, w, h)
    ref = new_renderer(world.model, h, w)
    try:
        for cam in range(world.model.ncam):
            off.update(d, cam)
            depth, geoms = off.depth_and_geoms()
            colour = off.colour()
            ref.update_scene(d, camera=cam)
            for flag in (
                mujoco.mjtRndFlag.mjRND_SHADOW,
                mujoco.mjtRndFlag.mjRND_REFLECTION,
                mujoco.mjtRndFlag.mjRND_SKYBOX,
            ):
                ref.scene.flags[flag] = 0
            want_colour = ref.render().copy()
            ref.enable_depth_rendering()
            want_depth = ref.render().copy()
            ref.disable_depth_rendering()
            ref.enable_segmentation_rendering()
            seg = ref.render()
            ref.disable_segmentation_rendering()
            want_geoms = np.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
            assert np.array_equal(depth, want_depth)
            assert np.array_equal(geoms, want_geoms)
            assert np.array_equal(colour, want_colour)
            assert (geoms >= 0).mean() > 0.5
    finally:
        off.close()
        ref.close()


def test_a_camera_is_drawn_again_only_when_the_world_moved(single):
    _, world, d, rig, _ = single
    first = rig.look(d, (*ACTING_VIEWS, WRIST), ACTING_SIZE, rgb=False)
    again = rig.look(d, (WRIST,), ACTING_SIZE, rgb=False)
    assert again.views[0] is first.views[-1]  # the world stood still: the same images
    assert not first.views[0].depth.flags.writeable
    moved = mujoco.MjData(world.model)
    moved.qpos[:] = d.qpos
    mug = world.model.body("obj/mug").jntadr[0]
    moved.qpos[world.model.jnt_qposadr[mug] + 1] += 0.05  # the mug 5 cm along y
    mujoco.mj_forward(world.model, moved)
    after = rig.look(moved, (ACTING_VIEWS[0],), ACTING_SIZE, rgb=False).views[0]
    assert after is not first.views[0]
    mug_id = rig.names.index("mug") + 1
    shift = after.points(after.instances == mug_id).mean(axis=0)
    shift -= first.views[0].points(first.views[0].instances == mug_id).mean(axis=0)
    assert 0.03 < shift[1] < 0.07 and abs(shift[0]) < 0.01


def test_a_known_object_is_perceived_within_tolerance(single):
    scene, world, d, rig, bundle = single
    perceived = perceive_objects(bundle)
    names = rig.instances
    for i, p in perceived.items():
        name = names[i]
        declared = scene.type_of(name)
        t = p.as_type(name, "upright")
        assert t.body.geom == declared.body.geom, name
        assert np.all(np.abs(t.body.box.size - declared.body.box.size) <= SIZE_TOL), name
        for side in ("on", "under", "left", "right", "front", "back"):
            assert t.parts[side].shape == declared.parts[side].shape, (name, side)
        true = d.xpos[world.body_ids[name]]
        assert np.linalg.norm(p.pose[:2, 3] - true[:2]) <= POSE_TOL, name
        assert abs(p.pose[2, 3] - true[2]) <= POSE_TOL, name
        assert abs(math.degrees(p.shape.yaw)) <= YAW_TOL_DEG, name
        handles = [m for m in t.members.values() if m.kind == "handle"]
        assert len(handles) == 1, name
        # (material from appearance errs now and then: measured in benchmarks/material_model.py)


@pytest.mark.parametrize("yaw_deg", [0.0, 37.0, 90.0, 160.0, 215.0, 300.0])
def test_a_mugs_handle_is_found_at_any_yaw(yaw_deg: float) -> None:
    data = {
        "name": "perception-mug",
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "table": {"type": "kitchen-table"},
        "slots": [
            {"name": "slot1", "position": [0.55, 0.0], "min": [0.3, -0.2], "max": [0.8, 0.2]}
        ],
        "objects": [{"name": "mug", "type": "glass-mug", "on": "slot1"}],
        "goal_base": "mug",
    }
    yaw = math.radians(yaw_deg)
    scene, world, d, rig = _world(data, yaw={"mug": yaw})
    try:
        (p,) = perceive_objects(rig.look(d, SURVEY_VIEWS, SURVEY_SIZE)).values()
    finally:
        rig.close()
    handles = [m for m in p.shape.members if m.kind == "handle"]
    assert len(handles) == 1
    h = handles[0].box
    centre = p.shape.to_world(((np.asarray(h.lo) + np.asarray(h.hi)) / 2)[None, :])[0]
    true_pose = d.xpos[world.body_ids["mug"]]
    declared = scene.type_of("mug").members["handle"].box.center  # object frame
    c, s = math.cos(yaw), math.sin(yaw)
    true_centre = true_pose[:2] + np.array([[c, -s], [s, c]]) @ declared[:2]
    assert np.linalg.norm(centre[:2] - true_centre) <= HANDLE_TOL
    assert np.linalg.norm(p.shape.origin[:2] - true_pose[:2]) <= POSE_TOL


def _alone(obj_type: str, yaw_deg: float = 0.0, on_it: str | None = None):
    """`obj_type` alone on a wide slot at `yaw_deg` (with `on_it` standing on it): the
    declared scene and the perceived object."""
    objects = [{"name": "obj", "type": obj_type, "on": "slot1"}]
    if on_it is not None:
        objects.append({"name": "top", "type": on_it, "on": "obj"})
    data = {
        "name": "perception-alone",
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "table": {"type": "kitchen-table"},
        "slots": [
            {"name": "slot1", "position": [0.55, 0.0], "min": [0.25, -0.35], "max": [0.85, 0.35]}
        ],
        "objects": objects,
        "goal_base": "obj",
    }
    scene, _, d, rig = _world(data, yaw={"obj": math.radians(yaw_deg)})
    try:
        seen = perceive_objects(rig.look(d, SURVEY_VIEWS, SURVEY_SIZE))
        (obj,) = (i for i, name in rig.instances.items() if name == "obj")
    finally:
        rig.close()
    return scene, seen[obj]


@pytest.mark.parametrize("yaw_deg", [0.0, 20.0, 90.0, 180.0, 250.0])
def test_a_trays_handle_bars_are_seen_as_thick_as_they_are(yaw_deg: float) -> None:
    """The bars on posts (2 cm by 12 cm) within `BAR_TOL` at any yaw: the posts' ends at
    the bar's inner face read them 2.5 cm, too thick for the rules' fingers; with the
    true thickness the rules grant the handle grasps the catalogue's tray has."""
    from utamp_gym.affordances.rules import object_facts

    scene, p = _alone("wooden-tray", yaw_deg)
    declared = scene.type_of("obj")
    bars = [m for m in p.shape.members if m.kind == "handle"]
    assert sorted(m.side for m in bars) in (["back", "front"], ["left", "right"])
    for m in bars:
        out = 0 if m.side in ("front", "back") else 1
        size = m.box.size
        assert abs(size[out] - declared.members["handle-front"].box.size[0]) <= BAR_TOL, size
        assert abs(size[1 - out] - declared.members["handle-front"].box.size[1]) <= SIZE_TOL
    grasps = {f[2] for f in object_facts(p.as_type("seen")) if f[0] == "canGraspFrom"}
    assert grasps >= {m.name for m in p.as_type("seen").members.values() if m.kind == "handle"}


def test_a_covered_pans_mass_is_its_shell() -> None:
    """A pan under a board: its opening, hidden, is judged from its flared wall, and its mass
    is that of a shell open at the top (it read 1.2 kg, a closed can, too heavy to hold by
    its handle: the rules dropped the handle grasp)."""
    from utamp_gym.affordances.rules import object_facts

    scene, p = _alone("frying-pan", on_it="cutting-board")
    declared = scene.type_of("obj")
    t = p.as_type("seen")
    assert not p.shape.top.visible and t.parts["on"].shape == "concave"
    assert np.allclose(t.parts["on"].center, (0.0, 0.0), atol=SIZE_TOL)
    assert abs(math.log(t.mass / declared.mass)) <= math.log(1.2), t.mass
    (handle,) = (m for m in t.members.values() if m.kind == "handle")
    assert ("canLift", "seen", handle.name) in object_facts(t)


def _perceived_type(scene_name: str, obj: str):
    """The declared and the perceived type of `obj` in a suite scene (seed 0)."""
    from utamp_gym.methods.perceived import perceive_scene
    from utamp_gym.suites import resolve_scene

    scene = resolve_scene(scene_name)
    return scene.type_of(obj), perceive_scene(scene, 0).planning.type_of(obj)


def test_a_pans_open_top_is_a_dish() -> None:
    """Its outer wall flares (in pick-place/003 its floor, measured in cells, came out too
    wide to say so, and it was read as a pot): it supports what spans its rim, and does
    not rest on its rim."""
    from utamp_gym.affordances.rules import object_facts

    _, t = _perceived_type("pick-place/003", "pan")
    assert t.parts["on"].shape == "concave"
    facts = object_facts(t)
    assert ("isSupportive", t.name, "on") in facts
    assert ("isSupportable", t.name, "on") not in facts


def test_a_bottles_wide_neck_is_a_neck() -> None:
    """A neck a third of the body's area across (its cells, quantised, cover more): found
    standing on the body's top, as wide and as high as declared (train/0137, never fitted)."""
    declared, t = _perceived_type("procedural-v1/train/0137", "obj1")
    neck = declared.members["neck"].box
    seen = [m for m in t.members.values() if m.kind != "body"]
    assert len(seen) == 1 and seen[0].box.min[2] == pytest.approx(neck.min[2], abs=0.005)
    assert seen[0].box.max[0] - seen[0].box.min[0] == pytest.approx(0.033, abs=0.005)
    assert t.body.box.max[2] == pytest.approx(neck.min[2], abs=0.005)


@pytest.mark.parametrize(
    ("scene_name", "obj"),
    [("procedural-v1/train/0042", "obj3"), ("procedural-v1/train/0087", "obj2")],
)
def test_a_plates_rim_left_beside_its_fitted_circle_widens_the_body(
    scene_name: str, obj: str
) -> None:
    """A plate's low rim gave the wall fit a circle centimetres short (17 cm for 23 cm) and a
    crescent of the rim was read as a handle (no rim grasp, no lift): the body widens to the
    arc (`walls.widen_to_arc`), and the plate is held by its two rim edges as declared."""
    declared, t = _perceived_type(scene_name, obj)
    assert not [m for m in t.members.values() if m.kind == "handle"]
    assert sorted(m.kind for m in t.members.values()) == ["body", "edge", "edge"]
    d, s = declared.body.box.size[0], t.body.box.size[0]
    assert abs(s - d) <= 0.01, (s, d)


@pytest.mark.parametrize("scene_name", ["pick-place/018", "pick-place/053"])
def test_a_board_fits_a_trays_well_as_declared(scene_name: str) -> None:
    """A board (24 cm and its 7 cm handle) in a tray's 32 cm well fits with 2 mm to spare:
    the board's face beside its handle (read up to 24.5 cm) and the well's inner edges
    (read 1 mm narrow) are measured to 1 mm along the board's length."""
    from utamp_gym.affordances.rules import p2p_supportive

    declared_board, board = _perceived_type(scene_name, "board")
    declared_tray, tray = _perceived_type(scene_name, "tray")
    length = board.bbox.size[0] - declared_board.bbox.size[0]  # along its handle
    assert abs(length) <= 0.001 and np.all(
        np.abs(board.bbox.size - declared_board.bbox.size) <= SIZE_TOL
    )
    well = np.asarray(declared_tray.surface_size("on"))
    error = np.abs(np.asarray(tray.surface_size("on")) - well)
    assert error[0] <= 0.001 and error[1] <= 0.002, error
    assert p2p_supportive(tray, "on", board, "under")


def test_the_lift_mass_is_cautious_only_where_the_density_leaves_lifting_open() -> None:
    from utamp_gym.perception.objects import LIFTABLE, lift_mass

    assert lift_mass(0.8, 1.2) == 0.8  # the board: liftable at any wood density
    assert lift_mass(1.45, 2.28) == 2.28  # the tray: it may be too heavy
    assert lift_mass(1.8, 2.8) == 1.8  # too heavy already at the nominal density
    assert lift_mass(1.0, LIFTABLE) == 1.0


def test_the_perceiver_needs_no_type_table(single):
    """The perceiver's only input is the bundle: with the scene's type table emptied (and
    the world's scene with it), it perceives the same objects."""
    scene, world, _, _, bundle = single
    before = {i: p.as_type("x").members.keys() for i, p in perceive_objects(bundle).items()}
    emptied = scene._replace(catalogue=Catalogue({}), custom_types={})
    info = world.info.__class__(**{**world.info.__dict__, "scene": emptied})
    object.__setattr__(world, "info", info)
    with pytest.raises(UnknownNameError):
        world.scene.type_of("mug")  # the table is gone
    views = ViewBundle(bundle.views, bundle.robot)  # images, intrinsics and poses only
    after = {i: p.as_type("x").members.keys() for i, p in perceive_objects(views).items()}
    assert after == before


def test_perception_never_imports_the_simulator() -> None:
    root = Path(utamp_gym.__file__).parent / "perception"
    for path in root.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.startswith("utamp_gym.sim"), path.name
                assert not node.module.startswith("mujoco"), path.name
            if isinstance(node, ast.Import):
                assert all(not a.name.startswith(("utamp_gym.sim", "mujoco")) for a in node.names)


def test_utamp2_perceived_plans_the_demo_scene() -> None:
    from utamp_gym.methods.perceived import plan_perceived
    from utamp_gym.planning.crosscheck import check_against_ground_truth
    from utamp_gym.suites import resolve_scene

    demo = resolve_scene("kitchen-demo")
    outcome, seen = plan_perceived(demo, 0)
    assert outcome.solved, outcome.reason
    assert seen is not None
    assert outcome.affordance_scores.f1 >= 0.95
    assert check_against_ground_truth(demo, outcome.plan).valid
    assert seen.accuracy["body"] == 1.0 and seen.accuracy["shape"] >= 0.95


def test_rgbd_pose_estimates_at_reset() -> None:
    from utamp_gym.grounding import physics_backend
    from utamp_gym.seeding import run_seed
    from utamp_gym.sim.measure import obj_pose, pose_change
    from utamp_gym.suites import resolve_scene

    scene = resolve_scene("pick-place/072")
    backend = physics_backend(perception="rgbd")
    try:
        backend.reset(scene, np.random.default_rng(run_seed(scene.name, 0)))
        st = backend.state
        for name in st.world.body_ids:
            shift, turn = pose_change(obj_pose(st, name), st.estimate(name))
            assert shift <= 0.006 and turn <= 3.0, (name, shift, turn)
        views = backend.cameras.look(st.data, (*ACTING_VIEWS, WRIST), ACTING_SIZE, rgb=False)
        assert all(v.rgb is None for v in views.views)
    finally:
        backend.close()


def test_utamp2_perceived_closed_loop_in_symbolic_grounding() -> None:
    """The planner policy believes the perceived affordances (renamed to the env's
    members) and reaches the goal of the demo scene."""
    from utamp_gym.eval.closed_loop import run_closed_loop

    out = run_closed_loop("kitchen-demo", "utamp2-perceived", grounding="symbolic")
    assert out.success, out.failure
    assert out.actions and all("seen" not in a for a in out.actions)


def test_an_rgbd_env_pickles_mid_episode() -> None:
    """The cameras' renderers are not pickled; the clone makes its own and sees the same."""
    import pickle

    import gymnasium as gym

    from utamp_gym.env.registry import register_envs

    register_envs()
    env = gym.make("UTampKitchen-v0", num_objects=3, perception="rgbd")
    _, info = env.reset(seed=0)
    env.step(int(np.flatnonzero(info["action_mask"])[0]))
    clone = pickle.loads(pickle.dumps(env))
    rng = np.random.default_rng(0)
    for _ in range(2):
        action = rng.choice(np.flatnonzero(env.unwrapped.action_masks()))
        one, two = env.step(action), clone.step(action)
        assert one[1] == two[1] and one[4]["macro_result"] == two[4]["macro_result"]
        assert np.allclose(one[0]["object_poses"], two[0]["object_poses"], atol=1e-6)
    env.close()
    clone.close()


def test_every_perceived_object_says_how_sure_it_is(single):
    _, _, _, _, bundle = single
    for p in perceive_objects(bundle).values():
        assert {"material", "mass", "robustness", "members"} <= set(p.confidence)
        assert all(0.0 <= v <= 1.0 for v in p.confidence.values())
        assert p.material.name not in p.alternatives["material"]
        assert set(p.alternatives) == set(p.confidence)
