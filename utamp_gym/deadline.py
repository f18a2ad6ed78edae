"""A wall-clock time limit shared by every phase of one planner call.

Why: `--timeout` must bound the whole call, so grounding, SAS writing and the search all
check the same deadline; the phase that runs out names itself in the `PlanningTimeout`.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

from utamp_gym.errors import PlanningTimeout

PHASES = ("scene", "problem", "grounding", "sas", "search", "postprocess")
"""Phases a planner call goes through, in order (`PlanningTimeout.phase` is one of them)."""


def check_timeout(timeout: float) -> float:
    """`timeout` as seconds; ValueError unless it is a positive finite number."""
    if not (isinstance(timeout, int | float) and math.isfinite(timeout) and timeout > 0):
        raise ValueError(f"timeout must be a positive finite number of seconds, got {timeout!r}")
    return float(timeout)


class Deadline(NamedTuple):
    """The moment `at` (on the `time.perf_counter` clock) a limit of `limit` seconds ends."""

    at: float
    limit: float

    @classmethod
    def after(cls, seconds: float, start: float | None = None) -> Deadline:
        """The deadline `seconds` after `start` (default: now)."""
        seconds = check_timeout(seconds)
        return cls((time.perf_counter() if start is None else start) + seconds, seconds)

    def remaining(self) -> float:
        """Seconds left (negative once passed)."""
        return self.at - time.perf_counter()

    def expired(self) -> bool:
        return time.perf_counter() > self.at

    def check(self, phase: str) -> None:
        """Raise `PlanningTimeout` naming `phase` if the deadline has passed."""
        if time.perf_counter() > self.at:
            raise PlanningTimeout(
                f"the time limit of {self.limit:g} s ran out during {phase}", phase=phase
            )
