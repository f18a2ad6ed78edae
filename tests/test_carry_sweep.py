"""Carrying an object that reaches far out of the hand (`measure.sweep_reach`): it comes
over its support at the height it was lifted to, above every other object, and then goes
down (`skills.place`). Lowered on the way to the pre-place pose, paddle boards carried by
their handles swept neighbours on seeds 0, 1 and 2 (procedural-v2/test-tasks/0067 a
tumbler, test-instances/0092 a food box on a chopping board)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from utamp_gym.kitchenware import generate
from utamp_gym.sim.measure import sweep_reach
from utamp_gym.sim.skills import SWEEP_REACH

CARRIES = {
    "procedural-v2/test-tasks/0067": (
        "(pick-support obj1 obj1-handle on left right back on slot3 under on)",
        "(place-support obj1 obj1-handle on left right back on under slot2 back on)",
        "obj3",
    ),
    "procedural-v2/test-instances/0092": (
        "(pick-support obj3 obj3-handle on left right back on slot3 under on)",
        "(place-support obj3 obj3-handle on left right back on under slot2 back on)",
        "obj1",
    ),
}


def test_the_sweep_reach_is_the_far_corner_from_the_grasp():
    board = generate("paddle-board", "v1", 3410810394)  # 0067's obj1, held by its handle
    handle = board.members["handle"].box
    middle = (handle.min[0] + handle.max[0]) / 2  # the board lies along x, the handle at -x
    far = math.hypot(board.bbox.max[0] - middle, board.bbox.max[1])
    assert sweep_reach(board, "handle") == pytest.approx(far, rel=1e-9)
    assert sweep_reach(board, "handle") > SWEEP_REACH
    assert sweep_reach(generate("mug", "v1", 3), "body") < SWEEP_REACH  # the hand covers it


def _carry(
    monkeypatch: pytest.MonkeyPatch, scene: str, reach: float, body_margin: bool = True
) -> tuple[bool, str]:
    from utamp_gym.robot.collision import CollisionChecker
    from utamp_gym.sim import skills
    from utamp_gym.sim.backend import MujocoBackend
    from utamp_gym.suites import resolve_scene

    monkeypatch.setattr(skills, "SWEEP_REACH", reach)
    if not body_margin:  # the checker as it was: a held body's compiled body_margin kept
        monkeypatch.setattr(CollisionChecker, "_widen_bodies", lambda self, geoms: None)
    pick, place, _ = CARRIES[scene]
    sim = MujocoBackend()
    try:
        sim.reset(resolve_scene(scene), np.random.default_rng(0))
        picked = sim.execute(pick)
        assert picked.success, picked.reason
        placed = sim.execute(place)
        return placed.success, placed.reason or ""
    finally:
        sim.close()


@pytest.mark.physics
@pytest.mark.parametrize("scene", sorted(CARRIES))
def test_a_board_carried_by_its_handle_passes_over_its_neighbour(monkeypatch, scene):
    ok, reason = _carry(monkeypatch, scene, SWEEP_REACH)
    assert ok, reason
    # lowered on the way, and checked with the held board's compiled body_margin (which
    # missed the neighbour 0-1 cm away, tests/test_collision_margin.py): it sweeps
    ok, reason = _carry(monkeypatch, scene, math.inf, body_margin=False)
    assert not ok and "toppled" in reason and CARRIES[scene][2] in reason
