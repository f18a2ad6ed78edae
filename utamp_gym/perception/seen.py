"""What fitting an object's shape reports, in its seen frame (`shape`): plain data.

Boxes, members, the top surface and the whole shape; a module of their own so that `shape`
(the fit) and `tops` (the top surface) share them without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from utamp_gym.perception.grid import rotate


@dataclass(frozen=True)
class SeenBox:
    """An axis-aligned box in the seen frame."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    @property
    def size(self) -> np.ndarray:
        return np.asarray(self.hi) - np.asarray(self.lo)


@dataclass(frozen=True)
class SeenMember:
    """A member as seen: kind (body, handle), side it sticks out of, box, primitive."""

    kind: str
    side: str  # front/back/left/right for a protrusion, "on" for a part on top, "" body
    box: SeenBox
    geom: str = "box"


@dataclass(frozen=True)
class SeenTop:
    """The seen top of the body: shape, usable surface size, height and centre (seen frame),
    the rim's width (for wells and cavities) and whether it was visible at all."""

    shape: str
    size: tuple[float, float]
    height: float
    center: tuple[float, float] = (0.0, 0.0)
    rim: float = 0.0
    floor: float = 0.0  # height of the floor of a cavity or well (0: none seen)
    visible: bool = True


@dataclass(frozen=True)
class SeenShape:
    """What the fitting found (see `shape`'s module docstring)."""

    yaw: float
    origin: np.ndarray  # world position of the seen frame's origin
    body: SeenMember
    members: tuple[SeenMember, ...]
    top: SeenTop
    bottom_size: tuple[float, float]  # footprint at the base (the hidden resting face)
    flare: float  # outer-wall radius growth from base to top, relative (cylinders)
    volume: float  # m^3 under the visible top surface, over the footprint
    area: float  # m^2, outer surface (body and members)
    covered: float  # fraction of the body's top hidden under other objects
    notes: tuple[str, ...] = field(default=())

    def to_world(self, local: np.ndarray) -> np.ndarray:
        """World points of seen-frame points (N, 3)."""
        xy = rotate(local[:, :2], self.yaw) + self.origin[:2]
        return np.column_stack([xy, local[:, 2] + self.origin[2]])


__all__ = ["SeenBox", "SeenMember", "SeenShape", "SeenTop"]
