"""Deprecated home of the open-loop episode runner: it moved to `utamp_gym.eval.episode`,
where a plan is played by `OpenLoopPolicy` through the env's one loop (this module's own
loop is gone). Importing a name from here still works for one release, with a
`DeprecationWarning`.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

_MOVED = (
    "EpisodeResult",
    "Execution",
    "StepRecord",
    "VIDEO_PERIOD",
    "VIDEO_SIZE",
    "episode_result",
    "execute_plan",
    "run_episode",
)


def __getattr__(name: str) -> Any:
    if name in _MOVED:
        warnings.warn(
            f"utamp_gym.sim.execute.{name} moved to utamp_gym.eval.episode.{name}; "
            "the old path goes away in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        # imported on use: sim/ itself depends on nothing above it
        return getattr(importlib.import_module("utamp_gym.eval.episode"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
