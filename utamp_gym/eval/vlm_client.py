"""Deprecated: moved to `utamp_gym.methods.vlm_client` (the methods' room); this path forwards its
names with a `DeprecationWarning` for one release."""

import utamp_gym.methods.vlm_client as _new
from utamp_gym.moved import forward

__getattr__, __dir__ = forward(__name__, _new)
