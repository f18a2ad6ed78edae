"""What a simulator reports about the world: plain data, no simulator objects.

Why plain data: perception (`utamp_gym.perception.abstraction`) turns this into symbolic
atoms, and any simulator (or a real robot's state estimator) can fill it in. The MuJoCo
backend produces it with `MujocoBackend.physical_state()`; a scene's declared initial
state produces it with `declared_state(scene)`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

#: `PhysicalState.supports` value of an object resting on the table outside every slot
TABLE = "table"
#: ... of an object lying on the floor (it fell off the table)
FLOOR = "floor"
#: an object tilted more than this (deg) from upright or inverted has toppled: the simulator
#: measures orientations (`utamp_gym.sim.world`) and perception abstracts them
#: (`utamp_gym.perception.abstraction`) with the same threshold
TILT_DEG = 20.0


@dataclass(frozen=True)
class Grasp:
    """How the hand holds an object: the grasped member and the palm / finger parts."""

    obj: str
    member: str  # member name in the object's type, e.g. "handle" (not "mug-handle")
    palm: str
    finger1: str
    finger2: str


@dataclass(frozen=True)
class PhysicalState:
    """The physical state of a kitchen table, as measured.

    * `poses`: object -> ``(x, y, z, qw, qx, qy, qz)`` of its frame in the world;
    * `supports`: object -> what carries its weight: another object, a table slot, `TABLE`
      (the table top outside every slot), `FLOOR`, or None (nothing: held or in the air);
    * `on_top`: object -> whether it rests on the top surface of its support (False: it
      rests *inside* it, e.g. a shaker in an upright mug; containment is not support);
    * `held`: the grasp of the object in the hand, or None;
    * `gripper_gap`: the finger gap (m).
    """

    poses: Mapping[str, tuple[float, ...]]
    supports: Mapping[str, str | None]
    on_top: Mapping[str, bool]
    held: Grasp | None = None
    gripper_gap: float = 0.08


__all__ = ["FLOOR", "TABLE", "TILT_DEG", "Grasp", "PhysicalState"]
