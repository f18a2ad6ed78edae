"""Deprecated: moved to `utamp_gym.dm.adapter` (the dm_control / dm_env room); this path
forwards its names with a `DeprecationWarning` for one release."""

import utamp_gym.dm.adapter as _new
from utamp_gym.moved import forward

__getattr__, __dir__ = forward(__name__, _new)
