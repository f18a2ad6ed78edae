"""Parts of a bounding box and axis-aligned boxes: the geometric vocabulary of U-TAMP.

An object's *parts* are the six sides of its bounding box plus its inside (`in`).
Frames: +x = front, +y = left, +z = on (up). Plain Python arithmetic (numpy loads only for
the array-valued `Box.size` and `Box.center`), so that the symbolic layer and `utamp plan`
do not import numpy.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    import numpy as np

PARTS: tuple[str, ...] = ("on", "under", "left", "right", "front", "back", "in")
SIDES: tuple[str, ...] = PARTS[:6]

#: outward unit normal of each side in the object frame
NORMALS: dict[str, tuple[int, int, int]] = {
    "on": (0, 0, 1),
    "under": (0, 0, -1),
    "left": (0, 1, 0),
    "right": (0, -1, 0),
    "front": (1, 0, 0),
    "back": (-1, 0, 0),
}
OPPOSITE: dict[str, str] = {
    "on": "under",
    "under": "on",
    "left": "right",
    "right": "left",
    "front": "back",
    "back": "front",
}
#: finger pairs considered for a grasp (one canonical order per axis)
FINGER_PAIRS: tuple[tuple[str, str], ...] = (("left", "right"), ("front", "back"), ("on", "under"))


def axis_of(side: str) -> int:
    """Index (0, 1, 2) of the axis a side's normal lies on."""
    return next(i for i, v in enumerate(NORMALS[side]) if v)


def _vec3(values: Iterable[float]) -> tuple[float, float, float]:
    x, y, z = values
    return x, y, z


def is_opposite(a: str, b: str) -> bool:
    """True if `a` and `b` are opposite sides of a box."""
    return OPPOSITE.get(a) == b


def is_adjacent(a: str, b: str) -> bool:
    """True if `a` and `b` are sides sharing an edge (perpendicular sides)."""
    return a in NORMALS and b in NORMALS and axis_of(a) != axis_of(b)


class Box(NamedTuple):
    """Axis-aligned box given by its min and max corners (metres)."""

    min: tuple[float, float, float]
    max: tuple[float, float, float]

    @property
    def size(self) -> np.ndarray:
        import numpy as np

        return np.asarray(self.max) - np.asarray(self.min)

    @property
    def center(self) -> np.ndarray:
        import numpy as np

        return (np.asarray(self.max) + np.asarray(self.min)) / 2.0

    @property
    def center_xy(self) -> tuple[float, float]:
        """x and y of the centre (plain floats)."""
        return (self.max[0] + self.min[0]) / 2.0, (self.max[1] + self.min[1]) / 2.0

    def union(self, other: Box) -> Box:
        lo, hi = map(min, self.min, other.min), map(max, self.max, other.max)
        return Box(_vec3(lo), _vec3(hi))

    def translated(self, offset: Sequence[float]) -> Box:
        o = [float(x) for x in offset]
        return Box(_vec3(map(operator.add, self.min, o)), _vec3(map(operator.add, self.max, o)))

    def flipped(self) -> Box:
        """The box after a half turn about the x axis through the origin (y -> -y, z -> -z)."""
        lo, hi = self.min, self.max
        return Box((float(lo[0]), -hi[1], -hi[2]), (float(hi[0]), -lo[1], -lo[2]))

    def face_size(self, side: str) -> tuple[float, float]:
        """Extents of the face `side` (the two axes orthogonal to its normal)."""
        i, j = (k for k in range(3) if k != axis_of(side))
        return float(self.max[i] - self.min[i]), float(self.max[j] - self.min[j])

    def contains_xy(self, other: Box, tol: float = 1e-9) -> bool:
        """True if `other`'s footprint lies inside this box's footprint."""
        return all(
            self.min[i] - tol <= other.min[i] and other.max[i] <= self.max[i] + tol for i in (0, 1)
        )

    def contains(self, other: Box, tol: float = 1e-9) -> bool:
        return all(
            self.min[i] - tol <= other.min[i] and other.max[i] <= self.max[i] + tol
            for i in range(3)
        )

    def gap_xy(self, other: Box) -> float:
        """The horizontal distance between the two footprints (0 if they overlap)."""
        dx = max(other.min[0] - self.max[0], self.min[0] - other.max[0], 0.0)
        dy = max(other.min[1] - self.max[1], self.min[1] - other.max[1], 0.0)
        return math.hypot(dx, dy)

    def overlaps_xy(self, other: Box, tol: float = 1e-9) -> bool:
        return all(
            self.min[i] < other.max[i] - tol and other.min[i] < self.max[i] - tol for i in (0, 1)
        )

    def touches_side(self, other: Box, side: str, gap: float) -> bool:
        """True if `other` lies beyond this box's `side`, within `gap`, overlapping it across."""
        ax = axis_of(side)
        sign = NORMALS[side][ax]
        distance = other.min[ax] - self.max[ax] if sign > 0 else self.min[ax] - other.max[ax]
        if not -1e-9 <= distance <= gap:
            return False
        return all(
            self.min[i] < other.max[i] and other.min[i] < self.max[i] for i in range(3) if i != ax
        )
