"""What the robot believes about object poses: the true pose plus estimation error.

Why: grasp, place and slide targets must come from an *estimate* of each object's pose, as a
camera-based pose estimator would give, not from the simulator's truth. The robot looks once
per skill (`new_look`): the first `PoseEstimator.estimate` of an object in a look is its true
pose plus fresh Gaussian noise drawn from the episode's generator — horizontal position (x
and y, each with standard deviation `noise` metres) and yaw
(`utamp_gym.backend.yaw_noise_deg(noise)` degrees) — plus any persistent *belief offset* an
injected fault put on that object. Height, roll and pitch are not perturbed: objects rest
on known, level surfaces (the estimate is plane-constrained, as tabletop pose estimators
usually are). Later estimates in the same look return the same pose, so one skill plans
with one consistent belief. A belief offset lasts until the robot grasps the object (it
then sees it in the hand) or an action involving the object fails (it looks again);
`forget` clears it and makes the next estimate of the object a new look. With
``noise == 0`` and no offset no random numbers are drawn (rollouts equal the noise-free
executor's).
"""

from __future__ import annotations

import math

import numpy as np

from utamp_gym.backend import yaw_noise_deg
from utamp_gym.contract.tracking import Beliefs, shifted

#: a close look's noise, as a fraction of the scene cameras' (module docstring)
CLOSE_FRACTION = 0.25


class PoseEstimator(Beliefs):
    """Noisy, possibly offset estimates of object poses (see the module docstring)."""

    def __init__(self, noise: float, rng: np.random.Generator) -> None:
        if not 0.0 <= noise < 1.0:
            raise ValueError(f"pose noise must be in [0, 1) m, got {noise!r}")
        super().__init__()
        self.noise, self.rng = float(noise), rng
        self.yaw_noise = math.radians(yaw_noise_deg(noise))

    def new_look(self) -> None:
        """Start a new look: the next estimate of every object is drawn afresh."""
        self._look.clear()

    def estimate(self, name: str, true_pose: np.ndarray) -> np.ndarray:
        """The estimate (4x4) of `name`'s pose in the current look, given its true pose."""
        seen = self._look.get(name)
        if seen is None:
            seen = self._look[name] = self._draw(name, true_pose)
        return seen.copy()

    def _draw(self, name: str, true_pose: np.ndarray) -> np.ndarray:
        shift, yaw = self.offsets.get(name, (np.zeros(3), 0.0))
        if self.noise > 0:
            shift = shift + np.array([*self.rng.normal(0.0, self.noise, 2), 0.0])
            yaw = yaw + float(self.rng.normal(0.0, self.yaw_noise))
        return shifted(true_pose, shift, yaw)

    def close_look(self, name: str, true_pose: np.ndarray) -> np.ndarray:
        """A look at `name` with the wrist camera: a fresh, closer estimate (module
        docstring) that the rest of this look uses; any belief offset is gone."""
        self.offsets.pop(name, None)
        out = true_pose.copy()
        if self.noise > 0:
            shift = np.array([*self.rng.normal(0.0, CLOSE_FRACTION * self.noise, 2), 0.0])
            yaw = float(self.rng.normal(0.0, CLOSE_FRACTION * self.yaw_noise))
            out = shifted(true_pose, shift, yaw)
        self._look[name] = out
        return out.copy()
