"""A held object that turns in the hand while carried (`measure.pivot_allowance`): the
extended domain's handle grasps carry a weight whose moment exceeds the pads' hanging hold,
and the object's far end sinks as it turns; the pick lifts it that much higher, so a
paddle board carried by its handle no longer sweeps a neighbour
(procedural-v2/test-instances/0092: it toppled a food box on seeds 0, 1 and 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from utamp_gym.affordances.hand import TORQUE_LIMIT, G
from utamp_gym.affordances.solids import centre_of_mass
from utamp_gym.kitchenware import generate
from utamp_gym.sim import measure
from utamp_gym.sim.measure import CARRY_TILT_DEG, pivot_allowance

SCENE = "procedural-v2/test-instances/0092"
PICK = "(pick-support obj3 obj3-handle on left right back on slot3 under on)"
PLACE = "(place-support obj3 obj3-handle on left right back on under slot2 back on)"


def _moment(t, member: str) -> float:
    box = t.members[member].box
    cx, cy = centre_of_mass(t)
    gx, gy = (box.min[0] + box.max[0]) / 2, (box.min[1] + box.max[1]) / 2
    return t.mass * G * math.hypot(cx - gx, cy - gy)


def test_the_allowance_is_the_far_corner_sinking_only_past_the_pads_hanging_hold():
    board = generate("paddle-board", "v1", 3391778779)  # 0092's obj3: 1.2 kg
    assert _moment(board, "handle") > TORQUE_LIMIT
    handle = board.members["handle"].box
    middle = (handle.min[0] + handle.max[0]) / 2  # the board lies along x, the handle at -x
    far = math.hypot(board.bbox.max[0] - middle, board.bbox.max[1])  # the far corners
    assert pivot_allowance(board, "handle") == pytest.approx(
        far * math.sin(math.radians(CARRY_TILT_DEG)), rel=1e-6
    )
    assert 0.04 < pivot_allowance(board, "handle") < 0.06
    mug = generate("mug", "v1", 3)  # held by its body or handle the pads hold it: no allowance
    assert _moment(mug, "body") <= TORQUE_LIMIT
    assert pivot_allowance(mug, "body") == 0.0


def _carry(monkeypatch: pytest.MonkeyPatch, tilt_deg: float) -> tuple[bool, str | None]:
    from utamp_gym.sim.backend import MujocoBackend
    from utamp_gym.suites import resolve_scene

    monkeypatch.setattr(measure, "CARRY_TILT_DEG", tilt_deg)
    sim = MujocoBackend()
    try:
        sim.reset(resolve_scene(SCENE), np.random.default_rng(0))
        picked = sim.execute(PICK)
        assert picked.success, picked.reason
        placed = sim.execute(PLACE)
        return placed.success, placed.reason
    finally:
        sim.close()


@pytest.mark.physics
@pytest.mark.slow
def test_a_board_carried_by_its_handle_passes_over_its_neighbour(monkeypatch):
    ok, reason = _carry(monkeypatch, CARRY_TILT_DEG)
    assert ok, reason
    ok, reason = _carry(monkeypatch, 0.0)  # without the allowance it sweeps the food box
    assert not ok and "toppled" in reason and "obj1" in reason
