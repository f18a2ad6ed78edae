"""Hand poses for tests of the arm: the TCP pointing straight down."""

from __future__ import annotations

import numpy as np

DOWN = np.diag([1.0, -1.0, -1.0])  # TCP z axis pointing down


def top_down(pos) -> np.ndarray:
    """The TCP pose (4x4) at `pos`, pointing straight down."""
    out = np.eye(4)
    out[:3, :3] = DOWN
    out[:3, 3] = pos
    return out
