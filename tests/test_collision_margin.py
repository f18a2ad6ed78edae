"""robot/collision.py and bodies of several geoms (MuJoCo's mid-phase bounds such a body by its
compiled ``body_margin``).

The checker widens a held object's ``body_margin`` with its geoms' margins at `attach` (and
restores it at `detach`), so a held board 5 mm from a tumbler counts at the 1 cm margin. The
robot's own bodies keep their compiled ``body_margin``: a finger (4 geoms) 5 mm from a tumbler
still gives no contact. Widening those too changes seeded rollouts of the paper's
Procedural and Slide physics envs (`benchmarks/rollout_identity.py`), so that part is left
open: its test is a strict xfail.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from utamp_gym.robot.collision import CollisionChecker
from utamp_gym.robot.kinematics import HOME_Q
from utamp_gym.robot.panda_mjcf import add_panda, set_home

BOX = mujoco.mjtGeom.mjGEOM_BOX
GAP = 0.005  # m between the held board and the tumbler: inside the 1 cm margin
MISSED = pytest.mark.xfail(
    strict=True,
    reason="not fixed: the robot's bodies keep their compiled body_margin (module docstring)",
)


def _world() -> tuple[mujoco.MjModel, mujoco.MjData, object]:
    """The Panda, a board of two boxes (a blade and a handle) and a 'tumbler' of four wall
    boxes, both free bodies away from the arm."""
    spec = mujoco.MjSpec()
    board = spec.worldbody.add_body(name="board", pos=[-0.5, 0.5, 0.05])
    board.add_freejoint()
    board.add_geom(name="blade", type=BOX, size=[0.1, 0.08, 0.01], mass=0.3)
    board.add_geom(name="handle", type=BOX, size=[0.05, 0.02, 0.01], pos=[0.15, 0, 0], mass=0.1)
    tumbler = spec.worldbody.add_body(name="tumbler", pos=[-0.5, -0.5, 0.05])
    tumbler.add_freejoint()
    for i, (x, y, sx, sy) in enumerate(
        [(0.035, 0, 0.004, 0.035), (-0.035, 0, 0.004, 0.035),
         (0, 0.035, 0.035, 0.004), (0, -0.035, 0.035, 0.004)]
    ):  # fmt: skip
        tumbler.add_geom(name=f"wall{i}", type=BOX, size=[sx, sy, 0.05], pos=[x, y, 0], mass=0.05)
    handles = add_panda(spec)
    model = spec.compile()
    ids = handles.bind(model)
    data = mujoco.MjData(model)
    set_home(model, data, ids)
    mujoco.mj_kinematics(model, data)
    return model, data, ids


def _place(model: mujoco.MjModel, data: mujoco.MjData, body: str, pos: np.ndarray) -> None:
    adr = model.jnt_qposadr[model.body(body).jntadr[0]]
    data.qpos[adr : adr + 3] = pos
    data.qpos[adr + 3 : adr + 7] = [1, 0, 0, 0]


@pytest.mark.parametrize("gap", [GAP, 0.02])
def test_a_held_board_counts_a_tumbler_inside_the_margin(gap: float) -> None:
    model, data, ids = _world()
    checker = CollisionChecker(model, ids, margin=0.01)
    q = np.array(HOME_Q)
    tcp = checker.tcp_pose(q)
    tcp_t_board = np.eye(4)
    tcp_t_board[:3, :3] = tcp[:3, :3].T  # the board level, axes along the world's
    tcp_t_board[:3, 3] = tcp[:3, :3].T @ [0.0, 0.0, -0.2]  # 20 cm below the TCP
    board = tcp[:3, 3] + [0.0, 0.0, -0.2]
    # the tumbler's -y wall (wall3) 'gap' beyond the blade's +y edge
    _place(model, data, "tumbler", board + np.array([0.0, 0.08 + gap + 0.035 + 0.004, 0.0]))
    checker.sync(data)
    checker.attach(model.body("board").id, tcp_t_board)
    hits = checker.contacts(q)
    names = checker.describe(hits)
    if gap < checker.margin:
        assert hits, "no contact"
        nearest = min(hits, key=lambda c: c.dist)
        assert checker.describe([nearest]) == "blade~wall3 (world, 5.0 mm)"
        assert not checker.is_valid(q)
    else:
        assert not hits and checker.is_valid(q), names
    checker.detach()
    assert checker.is_valid(q)  # put back away from the arm: nothing near the tumbler
    assert (
        checker.model.body_margin[model.body("board").id]
        == model.body_margin[model.body("board").id]
    )


def _gap(checker: CollisionChecker, body_a: int, body_b: int) -> float:
    """The smallest distance between the geoms of two bodies in the checker's state."""
    m, d = checker.model, checker.data
    ga = np.flatnonzero(m.geom_bodyid == body_a)
    gb = np.flatnonzero(m.geom_bodyid == body_b)
    return min(mujoco.mj_geomDistance(m, d, a, b, 1.0, None) for a in ga for b in gb)


@MISSED
def test_a_finger_counts_a_tumbler_inside_the_margin() -> None:
    model, data, ids = _world()
    checker = CollisionChecker(model, ids, margin=0.01)
    q = np.array(HOME_Q)
    checker.sync(data)  # the fingers open as at home
    checker.tcp_pose(q)
    finger, tumbler = model.body("panda/panda_leftfinger").id, model.body("tumbler").id
    above = checker.data.xpos[finger].copy()
    lo, hi = 0.0, 0.3  # how far below the finger's origin the tumbler stands GAP from it
    for _ in range(40):
        mid = (lo + hi) / 2
        _place(model, checker.data, "tumbler", above - [0.0, 0.0, mid])
        mujoco.mj_kinematics(checker.model, checker.data)
        lo, hi = (mid, hi) if _gap(checker, finger, tumbler) < GAP else (lo, mid)
    _place(model, checker.data, "tumbler", above - [0.0, 0.0, hi])
    mujoco.mj_kinematics(checker.model, checker.data)
    assert _gap(checker, finger, tumbler) == pytest.approx(GAP, abs=1e-6)
    assert checker.contacts(q), "no contact 5 mm from a finger at a 1 cm margin"
