"""The physics grounding's backend: the simulator composed with the robot's perception.

Why a module above both: the simulator (`utamp_gym.sim`) renders its cameras and reports
their parameters but fits no poses, and perception (`utamp_gym.perception`) fits poses to
views but never imports the simulator; the pose tracking is built here and handed to the
backend (`utamp_gym.contract.tracking`). `physics_backend` is the env's default backend
(`utamp_gym.backend.DEFAULT_BACKEND`): the env hands it its options, ``perception``
included, and it resolves that name with `TRACKING`.
"""

from __future__ import annotations

from typing import Any

from utamp_gym.backend import DEFAULT_PERCEPTION, PERCEPTION_MODES
from utamp_gym.contract.tracking import PoseTracking
from utamp_gym.errors import UnknownNameError
from utamp_gym.perception.tracking import rgbd_tracking
from utamp_gym.sim.backend import MujocoBackend

#: the env option ``perception`` -> the pose tracking handed to the simulator: None, the
#: simulator's own model (the true pose plus ``pose_noise``: `utamp_gym.sim.estimate`);
#: ``rgbd``, poses fitted to the rendered cameras (`utamp_gym.perception.tracking`)
TRACKING: dict[str, PoseTracking | None] = {"gaussian": None, "rgbd": rgbd_tracking}


def physics_backend(
    *, perception: str | PoseTracking = DEFAULT_PERCEPTION, **kwargs: Any
) -> MujocoBackend:
    """A `MujocoBackend` (keyword options as its own) whose pose estimates come from the
    tracking `perception` names (one of `PERCEPTION_MODES`) or is."""
    if not isinstance(perception, str):
        return MujocoBackend(perception=perception, **kwargs)
    if perception not in TRACKING:
        raise UnknownNameError("perception", perception, PERCEPTION_MODES)
    tracking = TRACKING[perception]
    return MujocoBackend(perception=DEFAULT_PERCEPTION if tracking is None else tracking, **kwargs)


__all__ = ["TRACKING", "physics_backend"]
