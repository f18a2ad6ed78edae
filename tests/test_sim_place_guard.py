"""The guarded descent of a place: a push at the place pose means it landed early only if
it is stronger than `CONTACT_N` and than the object's own weight, which a support can carry
without being pressed (a pan held by its handle sags until its far edge rests on the tray).
"""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.sim import skills
from utamp_gym.sim.backend import MujocoBackend
from utamp_gym.sim.control import ArmDriver
from utamp_gym.sim.skills import CONTACT_N, landed_early
from utamp_gym.suites import resolve_scene


@pytest.mark.parametrize(
    ("push", "weight", "early"),
    [
        (5.3, 7.8, False),  # a sagging pan: the tray carries 5.3 N of its 7.8 N
        (7.6, 5.9, True),  # a board pressed into the pan beyond its weight
        (CONTACT_N + 1, 1.2, True),  # a shaker pressed onto a rim
        (CONTACT_N - 1, 1.2, False),  # ... within the guard's tolerance
        (CONTACT_N + 0.5, CONTACT_N + 1, False),
    ],
)
def test_a_push_is_an_early_landing_beyond_contact_n_and_the_weight(push, weight, early):
    assert landed_early(push, weight) is early


@pytest.mark.physics
def test_a_pan_sagging_onto_the_tray_is_placed_at_the_first_descent(monkeypatch):
    scene = resolve_scene("pick-place/003")  # tray | pan
    pick = "(pick-support pan pan-handle on left right back on slot2 under on)"
    place = "(place-support pan pan-handle on left right back on under tray back on)"
    lowered: list[float] = []
    move_line = ArmDriver.move_line

    def counting(self: ArmDriver, line, speed: float, acc: float) -> None:
        if (speed, acc) == skills.PLACE:  # a descent, or the back-up before another one
            lowered.append(line.length)
        move_line(self, line, speed, acc)

    monkeypatch.setattr(ArmDriver, "move_line", counting)
    sim = MujocoBackend(pose_noise=0.0)
    sim.reset(scene, np.random.default_rng(0))
    assert sim.execute(pick).success
    lowered.clear()
    result = sim.execute(place)
    assert result.success, result.reason
    assert len(lowered) == 1
    assert sim.stacked_on_tray() == ["pan"]
    sim.close()
