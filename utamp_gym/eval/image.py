"""Deprecated: moved to `utamp_gym.methods.image` (the methods' room); this path forwards its
names with a `DeprecationWarning` for one release."""

import utamp_gym.methods.image as _new
from utamp_gym.moved import forward

__getattr__, __dir__ = forward(__name__, _new)
