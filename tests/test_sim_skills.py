"""Decoding macro-action symbols into poses, the pick / place skills, and failure detection.

The physics tests look only at what the simulation measured (poses, contacts, the
finger gap); the symbolic layer never decides whether a skill worked.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from utamp_gym.errors import GroundingError, SimulationError, UnknownNameError
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import load_catalogue
from utamp_gym.scene.io import load_scene, scene_from_dict
from utamp_gym.sim.decode import (
    GRASP_DEPTH,
    PREGRASP,
    GraspSymbols,
    footprint_centre,
    grasp_candidates,
    hand_for_object,
    parse_action,
    place_object_pose,
    slide_vector,
    support_point,
    world_aabb,
)

CAT = load_catalogue()
INVERTED = np.diag([1.0, -1.0, -1.0])
X = np.array([1.0, 0.0, 0.0])


def pose(pos, rot=None, yaw: float = 0.0) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    out = np.eye(4)
    out[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ (np.eye(3) if rot is None else rot)
    out[:3, 3] = pos
    return out


@pytest.fixture(scope="module")
def demo():
    return load_scene(asset_path("scenes", "kitchen-demo.toml"))


# ------------------------------------------------------------------ decoding (pure)
def test_palm_on_top_grasps_top_down():
    salt = CAT["salt-shaker"]
    g = grasp_candidates(salt, GraspSymbols("s", "body", "on", "left", "right"),
                         pose([0.5, 0.2, 0.0]), prefer_x=X)[0]  # fmt: skip
    np.testing.assert_allclose(g.tcp[:3, 2], [0, 0, -1], atol=1e-12)  # approach straight down
    np.testing.assert_allclose(abs(g.tcp[:3, 1] @ [0, 1, 0]), 1.0)  # fingers open along y
    np.testing.assert_allclose(g.tcp[:3, 0], X, atol=1e-12)  # the preferred wrist turn
    assert np.linalg.det(g.tcp[:3, :3]) == pytest.approx(1.0)
    np.testing.assert_allclose(g.tcp[:3, 3], [0.5, 0.2, 0.11 - GRASP_DEPTH], atol=1e-12)
    np.testing.assert_allclose(g.pregrasp[:3, 3] - g.tcp[:3, 3], [0, 0, PREGRASP], atol=1e-12)
    assert g.width == pytest.approx(0.045) and g.width < g.opening <= 0.08


def test_finger_axis_follows_the_finger_part_and_the_object_yaw():
    salt, yaw = CAT["salt-shaker"], math.radians(30)
    sym = GraspSymbols("s", "body", "on", "front", "back")
    both = grasp_candidates(salt, sym, pose([0.5, 0.0, 0.0], yaw=yaw), prefer_x=X)
    front = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    for g in both:
        assert abs(g.tcp[:3, 1] @ front) == pytest.approx(1.0)
    np.testing.assert_allclose(both[0].tcp[:3, 1], -both[1].tcp[:3, 1])
    assert both[0].tcp[:3, 0] @ X >= both[1].tcp[:3, 0] @ X


def test_inverted_mug_palm_under_is_still_top_down():
    mug = CAT["glass-mug"]
    at = pose([0.6, 0.38, 0.10], INVERTED)  # resting on its rim, the bottom faces up
    g = grasp_candidates(mug, GraspSymbols("m", "body", "under", "left", "right"), at,
                         prefer_x=X)[0]  # fmt: skip
    np.testing.assert_allclose(g.tcp[:3, 2], [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(g.tcp[:3, 3], [0.6, 0.38, 0.10 - GRASP_DEPTH], atol=1e-12)
    # the loop handle is hollow in its middle: the fingers go to its outer grip bar
    h = grasp_candidates(mug, GraspSymbols("m", "handle", "under", "left", "right"), at,
                         prefer_x=X)[0]  # fmt: skip
    np.testing.assert_allclose(h.tcp[:3, 2], [0, 0, -1], atol=1e-12)
    assert h.tcp[0, 3] == pytest.approx(0.6 - 0.064)
    assert h.width == pytest.approx(0.014)


def test_fingertips_stay_above_the_support():
    board = CAT["cutting-board"]  # a 2 cm thick handle: half of it is less than the depth
    g = grasp_candidates(board, GraspSymbols("b", "handle", "on", "left", "right"),
                         pose([0.2, -0.38, 0.0]), prefer_x=X)[0]  # fmt: skip
    assert g.tcp[2, 3] - 0.0095 >= 0.003 - 1e-12  # pads end 3 mm above the table


def test_place_target_is_centred_on_the_support():
    tray, salt, board = CAT["wooden-tray"], CAT["salt-shaker"], CAT["cutting-board"]
    tray_at = pose([0.5, 0.02, 0.0], yaw=0.01)
    top = support_point(tray, "on", tray_at)
    np.testing.assert_allclose(top, [0.5, 0.02, 0.012], atol=1e-12)  # the tray's floor
    held = pose([0.3, 0.3, 0.25], yaw=0.1)
    target = place_object_pose(salt, held, top, drop=0.0)
    np.testing.assert_allclose(footprint_centre(salt, target), top[:2], atol=1e-12)
    assert world_aabb(salt.bbox, target)[0][2] == pytest.approx(0.012)
    np.testing.assert_allclose(target[:3, :3], held[:3, :3], atol=1e-12)  # yaw kept
    # the board's footprint includes its handle: its frame sits off the tray's centre
    b = place_object_pose(board, pose([0.3, 0.3, 0.2]), top, drop=0.0, yaw=0.0)
    np.testing.assert_allclose(b[:2, 3], [0.535, 0.02], atol=1e-12)
    tcp_t_obj = pose([0.01, 0.0, 0.05], INVERTED)
    np.testing.assert_allclose(hand_for_object(b, tcp_t_obj) @ tcp_t_obj, b, atol=1e-12)


def test_place_on_an_inverted_mug_and_not_on_a_downward_part():
    mug, salt = CAT["glass-mug"], CAT["salt-shaker"]
    top = support_point(mug, "under", pose([0.6, 0.38, 0.10], INVERTED))
    np.testing.assert_allclose(top, [0.6, 0.38, 0.10], atol=1e-12)
    target = place_object_pose(salt, pose([0.3, 0.3, 0.3], INVERTED), top, drop=0.0)
    assert target[2, 2] == pytest.approx(-1.0)  # an inverted object stays inverted
    assert world_aabb(salt.bbox, target)[0][2] == pytest.approx(0.10)
    with pytest.raises(GroundingError, match="does not face up"):
        support_point(mug, "under", pose([0.6, 0.38, 0.0]))


def test_slide_vector_takes_the_footprint_to_the_space():
    tray = CAT["wooden-tray"]
    np.testing.assert_allclose(
        slide_vector(tray, pose([0.95, 0.01, 0.0]), np.array([0.5, 0.0])), [-0.45, -0.01, 0]
    )


def test_parse_action(demo):
    act = parse_action("(place-support salt salt-body on left right back on under mug back under)",
                       demo)  # fmt: skip
    assert (act.kind, act.grasp.member, act.support, act.support_part) == (
        "place-support", "body", "mug", "under")  # fmt: skip
    slide = parse_action("(slide-support tray tray-handle-back on front back back slot1 under on "
                         "space1 back front under)", demo)  # fmt: skip
    assert (slide.grasp.finger1, slide.support, slide.space) == ("front", "slot1", "space1")
    with pytest.raises(UnknownNameError, match="tray-handle-front"):
        parse_action("(pick-support tray tray-lid on front back back on slot1 under on)", demo)
    with pytest.raises(UnknownNameError, match="valid: pick-support"):
        parse_action("(stack salt mug)", demo)
    with pytest.raises(GroundingError, match="takes 10 arguments"):
        parse_action("(pick-support salt salt-body on left right)", demo)


# ------------------------------------------------------------------ skills in physics
physics = pytest.mark.physics
PICK_SALT = "(pick-support salt salt-body on left right back on slot5 under on)"
PLACE_SALT_ON_MUG = "(place-support salt salt-body on left right back on under mug back under)"
PLACE_SALT_ON_TRAY = "(place-support salt salt-body on left right back on under tray back on)"


#: the suites' side slots 4 and 5 and their workspace, for scenes written in a test
SIDE_SLOTS = [
    {"name": "slot4", "position": [0.6, 0.38], "min": [0.44, 0.22], "max": [0.82, 0.52]},
    {"name": "slot5", "position": [0.6, -0.38], "min": [0.44, -0.52], "max": [0.82, -0.22]},
]
WORKSPACE = {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]}


@pytest.fixture
def backend():
    from utamp_gym.sim.backend import MujocoBackend

    sim = MujocoBackend()
    yield sim
    sim.close()


def _on(sim, name: str):
    from utamp_gym.sim.world import rests_on_top, stack_from_poses

    st = sim.state
    support = stack_from_poses(st.world, st.data)[name]
    return support, rests_on_top(st.world, st.data, name, support)


@physics
def test_backend_protocol_and_initial_state(backend, demo):
    from utamp_gym.backend import PhysicsBackend

    with pytest.raises(SimulationError, match="reset"):
        backend.object_poses()
    backend.reset(demo, np.random.default_rng(0))
    assert isinstance(backend, PhysicsBackend)  # `cameras` exists from the first reset on
    assert set(backend.cameras.instances.values()) == set(demo.object_names)
    poses = backend.object_poses()
    assert set(poses) == set(demo.object_names) and all(p.shape == (7,) for p in poses.values())
    assert backend.joint_positions().shape == (9,)
    assert backend.stacked_on_tray() == []
    image = backend.render(96, 64)
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8 and image.std() > 0
    bad = backend.execute("(pick-support plate plate-body on left right back on slot5 under on)")
    assert not bad.success and "plate" in bad.reason
    nothing = backend.execute(PLACE_SALT_ON_MUG)
    assert not nothing.success and "holds nothing" in nothing.reason


@physics
def test_pick_then_place_salt_on_the_inverted_mug(backend, demo):
    backend.reset(demo, np.random.default_rng(0))
    picked = backend.execute(PICK_SALT)
    assert picked.success, picked.reason
    assert set(picked.timings) == {"ik_s", "plan_s", "sim_s", "wall_s", "sim_time_s"}
    assert _on(backend, "salt")[0] is None  # in the hand, nothing under it
    assert backend.joint_positions()[7:].sum() == pytest.approx(0.045, abs=0.003)  # squeezing
    placed = backend.execute(PLACE_SALT_ON_MUG)
    assert placed.success, placed.reason
    assert _on(backend, "salt") == ("mug", True)
    assert _on(backend, "mug") == ("slot4", True)
    quat = backend.object_poses()["salt"][3:]
    assert abs(quat[0]) > math.cos(math.radians(5) / 2)  # standing upright


@physics
def test_the_tray_is_not_liftable_by_one_handle(backend, demo):
    backend.reset(demo, np.random.default_rng(0))
    # symbolically invalid in U-TAMP-2 (the tray is not liftable), but physics must try it
    res = backend.execute(
        "(pick-support tray tray-handle-back on front back back on slot1 under on)"
    )
    assert not res.success
    assert "tray" in res.reason and "not liftable" in res.reason
    assert backend.state.held is None  # it let go
    assert _on(backend, "tray")[0] == "slot1"
    assert backend.execute(PICK_SALT).success  # the robot recovered


@physics
def test_upright_mug_falls_off_the_shaker(backend):
    scene = scene_from_dict({
        "name": "mug-on-salt", "slots": SIDE_SLOTS, "workspace": WORKSPACE,
        "objects": [{"name": "mug", "type": "glass-mug", "on": "slot4"},
                    {"name": "salt", "type": "salt-shaker", "on": "slot5"}],
    })  # fmt: skip
    backend.reset(scene, np.random.default_rng(1))
    picked = backend.execute("(pick-support mug mug-body on left right back on slot4 under on)")
    assert picked.success, picked.reason
    res = backend.execute("(place-support mug mug-body on left right back on under salt back on)")
    assert not res.success and "mug fell off salt" in res.reason
    assert _on(backend, "mug")[0] != "salt"


@physics
def test_a_held_object_counts_in_motion_planning(backend, demo):
    backend.reset(demo, np.random.default_rng(0))
    assert backend.execute(PICK_SALT).success
    st = backend.state
    arm, held = st.arm, st.held
    low = np.diag([1.0, -1.0, -1.0, 1.0])
    low[:3, 3] = [0.45, -0.15, 0.07]  # hand 7 cm over the free table: the salt would be in it
    q_low = next(arm.ik_solutions(low, None))
    checker = arm.sync(arm.free, gap=arm.gap())
    assert checker.is_valid(q_low)  # the bare arm fits
    checker.attach(held.body, held.tcp_t_obj)
    try:
        assert not checker.is_valid(q_low)
        assert any(st.world.object_of_geom(c.geom1) == "salt" for c in checker.contacts(q_low))
    finally:
        checker.detach()
    with pytest.raises(GroundingError, match="goal configuration in collision"):
        arm.transfer(q_low, held=(held.body, held.tcp_t_obj))


@physics
def test_a_failed_place_keeps_the_object_in_the_hand(backend, demo):
    backend.reset(demo, np.random.default_rng(0))
    assert backend.execute(PICK_SALT).success
    # the inverted mug's `on` part (its rim) faces down: nothing can be put on it
    res = backend.execute("(place-support salt salt-body on left right back on under mug back on)")
    assert not res.success and "does not face up" in res.reason
    assert backend.state.held is not None and backend.state.held.obj == "salt"
    placed = backend.execute(PLACE_SALT_ON_MUG)
    assert placed.success, placed.reason


@physics
def test_closing_on_nothing_is_a_failed_grasp(backend):
    flat = {s: {"shape": "flat"} for s in ("under", "left", "right", "front", "back")}
    crate = {
        "mass": 1.0, "material": "wood", "robustness": "sturdy",
        "members": {  # "hole": an edge member inside the open crate, realised by nothing
            "body": {"min": [-0.15, -0.15, 0.0], "max": [0.15, 0.15, 0.1]},
            "hole": {"kind": "edge", "min": [-0.015, -0.015, 0.03], "max": [0.015, 0.015, 0.08]},
        },
        "parts": {**flat, "on": {"shape": "open"}},
    }  # fmt: skip
    scene = scene_from_dict({
        "name": "empty-crate", "types": {"crate": crate},
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "slots": [{"name": "slot1", "position": [0.5, 0.0], "min": [0.3, -0.2], "max": [0.7, 0.2]}],
        "objects": [{"name": "crate", "type": "crate", "on": "slot1"}],
    })  # fmt: skip
    backend.reset(scene, np.random.default_rng(0))
    res = backend.execute("(pick-support crate crate-hole on left right back on slot1 under on)")
    assert not res.success and "closed on nothing" in res.reason and "crate" in res.reason
    # the first miss was undone and the grasp tried again, once, before failing
    assert len(res.retries) == 1 and "closed on nothing" in res.retries[0]
    assert backend.state.held is None
    assert _on(backend, "crate") == ("slot1", True)


PICK_MUG = "(pick-support mug mug-body under left right back under slot4 on on)"


@physics
def test_a_grasp_that_lands_on_the_object_backs_off_and_grasps_again(backend, demo, monkeypatch):
    """The robot believes the inverted mug 2 cm off along the finger axis: with the wrist
    camera's re-aim switched off, a finger lands on its rim and holds the hand centimetres
    short of the grasp pose, the hand backs off, looks again and grasps the mug it left
    standing; with the true belief no retry is needed."""
    from utamp_gym.sim import relook

    monkeypatch.setattr(relook, "aim_grasp", lambda st, sym, g, plan, replan: plan)
    backend.reset(demo, np.random.default_rng(0))
    assert backend.execute(PICK_MUG).retries == ()
    backend.reset(demo, np.random.default_rng(0))
    backend.state.estimator.offset("mug", np.array([0.0, 0.02, 0.0]), 0.0)
    res = backend.execute(PICK_MUG)
    assert res.success, res.reason
    assert len(res.retries) == 1
    assert "the hand stopped short of the body of mug" in res.retries[0]
    assert backend.state.held is not None and backend.state.held.obj == "mug"


@physics
def test_the_wrist_camera_re_aims_a_grasp_before_the_descent(backend, demo):
    """The same wrong belief, with the wrist camera: its close look at the pre-grasp pose
    corrects the aim, and the grasp succeeds at once (no finger lands on the rim)."""
    backend.reset(demo, np.random.default_rng(0))
    backend.state.estimator.offset("mug", np.array([0.0, 0.02, 0.0]), 0.0)
    res = backend.execute(PICK_MUG)
    assert res.success, res.reason
    assert res.retries == ()
    assert "mug" not in backend.state.estimator.offsets  # the close look ended the belief


@physics
@pytest.mark.parametrize("aim_room", [True, False])
def test_the_wrist_camera_re_aims_a_wrap_off_by_less_than_the_aim_shift(
    demo, monkeypatch, aim_room
):
    """A grasp 1.5 mm off along the finger axis (less than `AIM_SHIFT`) with 1 mm of room
    for the open fingers: the close look re-aims it because it would not fit, and the
    grasp succeeds at once; an aim that ignored the room is refused by the check before
    the fingers close and costs a retry."""
    from utamp_gym.sim import relook
    from utamp_gym.sim.backend import MujocoBackend
    from utamp_gym.sim.decode import FINGER_CLEARANCE, MAX_OPENING

    assert relook.AIM_SHIFT > 0.0015
    width = float(CAT["glass-mug"].members["body"].box.size[1])  # between left and right
    opening = min(MAX_OPENING, width + 2 * FINGER_CLEARANCE)
    monkeypatch.setattr(relook, "CHECK_MARGIN", (opening - width) / 2 - 0.001)  # 1 mm of room
    if not aim_room:
        monkeypatch.setattr(relook, "AIM_ROOM_SHARE", 10.0)
    sim = MujocoBackend(pose_noise=0.0)  # exact looks: only the belief is off
    try:
        sim.reset(demo, np.random.default_rng(0))
        sim.state.estimator.offset("mug", np.array([0.0, 0.0015, 0.0]), 0.0)
        res = sim.execute(PICK_MUG)
    finally:
        sim.close()
    assert res.success, res.reason
    if aim_room:
        assert res.retries == ()
    else:
        assert len(res.retries) == 1 and "wrist camera saw the body of mug" in res.retries[0]


@physics
def test_a_placement_on_a_slot_goes_along_when_a_neighbour_stands_at_its_position(backend):
    """A shaker stands 5 cm from slot4's position: the mug cannot be set down centred on
    the position, so it is set down at the nearest spot of the slot with room, and the
    shaker is not touched."""
    scene = scene_from_dict({
        "name": "crowded-slot", "slots": SIDE_SLOTS, "workspace": WORKSPACE,
        "objects": [{"name": "mug", "type": "glass-mug", "on": "slot5"},
                    {"name": "salt", "type": "salt-shaker", "on": "slot4",
                     "position": [0.6, 0.33]}],
    })  # fmt: skip
    backend.reset(scene, np.random.default_rng(1))
    salt = backend.state.data.xpos[backend.state.world.body_ids["salt"]].copy()
    picked = backend.execute("(pick-support mug mug-body on left right back on slot5 under on)")
    assert picked.success, picked.reason
    res = backend.execute("(place-support mug mug-body on left right back on under slot4 back on)")
    assert res.success, res.reason
    assert _on(backend, "mug") == ("slot4", True)
    st = backend.state
    mug = st.data.xpos[st.world.body_ids["mug"]]
    assert np.hypot(mug[0] - 0.6, mug[1] - 0.38) > 0.02  # not at the position
    np.testing.assert_allclose(st.data.xpos[st.world.body_ids["salt"]], salt, atol=0.003)


@physics
def test_a_slot_takes_an_object_inside_its_region_with_its_members_in_reach(backend):
    """slot5 lies 0.71 m out and is 38 x 30 cm. A pot's lid set down there lies inside the
    slot's region with every member within `MEMBER_REACH`, and is picked up again; a 43 cm
    tray, which the slot's region cannot hold (a tray set down square on the slot's position
    once put its far handle 0.89 m out, where no arm reached it), is refused before the arm
    moves, as the rules refuse it; and so is the tray set down on the lid there, which the
    rules forbid but physics once carried out, stranding the tray beyond the arm's reach."""
    from utamp_gym.scene.geometry import Box
    from utamp_gym.sim.decode import world_aabb
    from utamp_gym.sim.measure import obj_pose
    from utamp_gym.suites import resolve_scene
    from utamp_gym.symbolic.slots import MEMBER_REACH, admits, usable_region

    scene = resolve_scene("procedural-v1/test-families/0071")
    slot5 = next(s for s in scene.slots if s.name == "slot5")
    assert not admits(scene, slot5, scene.type_of("base"), "under")
    assert admits(scene, slot5, scene.type_of("obj2"), "under")
    backend.reset(scene, np.random.default_rng(0))
    for action in (
        "(pick-support obj2 obj2-lid on back front back on base under on)",
        "(place-support obj2 obj2-lid on back front back on under slot5 back on)",
    ):
        res = backend.execute(action)
        assert res.success, (action, res.reason)
    assert _on(backend, "obj2") == ("slot5", True)
    st = backend.state
    pose = obj_pose(st, "obj2")
    t = st.world.scene.type_of("obj2")
    for member in t.members.values():
        centre = pose[:3, :3] @ np.asarray(member.box.center) + pose[:3, 3]
        assert math.hypot(centre[0], centre[1]) <= MEMBER_REACH + 0.01, member.name
    lo, hi = world_aabb(t.bbox, pose)
    assert usable_region(scene, slot5).contains_xy(Box(tuple(lo), tuple(hi)), tol=0.005)
    res = backend.execute(
        "(pick-support base base-handle-back on back front back on slot1 under on)"
    )
    assert res.success, res.reason
    res = backend.execute(
        "(place-support base base-handle-back on back front back on under slot5 back on)"
    )
    assert not res.success and res.reason.startswith("no spot of slot5 holds base"), res.reason
    held = backend.physical_state().held
    assert held is not None and held.obj == "base"  # refused before the arm moved: still held
    # nor is it set down on the lid in slot5, which would put its far handle as far out
    res = backend.execute(
        "(place-support base base-handle-back on back front back on under obj2 back on)"
    )
    assert not res.success and "beyond the hand's reach" in res.reason, res.reason
    held = backend.physical_state().held
    assert held is not None and held.obj == "base"


@physics
@pytest.mark.parametrize(
    "name",
    [
        "procedural-v1/test-count/0063",  # a plate in a larger plate's well is picked by its rim
        "procedural-v1/test-count/0008",  # a plate held by its rim is set down in another's well
    ],
)
def test_plates_pinched_by_the_rim_in_a_larger_plates_well(name):
    """The lower plate's rim rises where the outer finger goes: the pinch is made higher up
    on the rim, the plate let go higher above the well (IK found no grasp or placement at
    the usual heights before); physics then carries the whole plan out."""
    from utamp_gym.agents.runs import run_episode

    res = run_episode(name, "utamp2-rules", seed=0, pose_noise=0.0)
    assert any("rim-back" in a and "place-support" in a for a in res.plan)
    assert res.success, res.failure


@physics
def test_the_wrist_camera_aborts_a_grasp_whose_object_moved(backend, demo, monkeypatch):
    """The shaker is pushed 2.5 cm aside while the hand descends onto it (as a finger would
    push a light shaker): the wrist camera's look before closing sees it outside the open
    fingers, the hand backs off, and the pick retries after a new look."""
    from utamp_gym.sim import relook

    original = relook.grasp_offset
    calls = []

    def pushed(st, sym, g):
        if not calls:  # the first check: move the shaker before the camera looks
            adr = st.world.qpos_adr["salt"]
            st.data.qpos[adr + 1] += 0.025
            import mujoco

            mujoco.mj_forward(st.world.model, st.data)
        calls.append(1)
        return original(st, sym, g)

    monkeypatch.setattr(relook, "grasp_offset", pushed)
    backend.reset(demo, np.random.default_rng(0))
    res = backend.execute(PICK_SALT)
    assert res.success, res.reason
    assert len(res.retries) == 1 and "wrist camera saw the body of salt" in res.retries[0]
    assert backend.state.held is not None and backend.state.held.obj == "salt"


def test_a_line_path_splits_at_a_waypoint():
    from utamp_gym.sim.control import LinePath

    line = LinePath(np.array([0.0, 0.01, 0.02, 0.03]), np.arange(4.0)[:, None] * np.ones(7))
    test, rest = line.split(0.01)
    assert test.s.tolist() == [0.0, 0.01] and test.q[:, 0].tolist() == [0.0, 1.0]
    assert rest.s.tolist() == pytest.approx([0.0, 0.01, 0.02]) and rest.q[0, 0] == 1.0
    assert line.split(0.0)[0].length == pytest.approx(0.01)  # never an empty first part


# ------------------------------------------------------------------ failure detection
# Both failures are produced physically (a force on the held object, a knock on the base
# of a stack) and detected only from the simulated poses, velocities and finger gap.
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
