"""Deprecated: moved to `utamp_gym.symbolic.scene_cache` (the symbolic world model's room); this
path forwards its names with a `DeprecationWarning` for one release."""

import utamp_gym.symbolic.scene_cache as _new
from utamp_gym.moved import forward

__getattr__, __dir__ = forward(__name__, _new)
