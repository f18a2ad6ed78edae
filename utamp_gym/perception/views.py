"""Deprecated: moved to `utamp_gym.contract.views` (the types both the simulator and
perception use); this path forwards its names with a `DeprecationWarning` for one release."""

import utamp_gym.contract.views as _new
from utamp_gym.moved import forward

__getattr__, __dir__ = forward(__name__, _new)
