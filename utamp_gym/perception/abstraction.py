"""`perceive`: the U-TAMP domain's state atoms from a physical state (poses, supports, grasp).

The abstraction (the same for a scene's declared state and for a simulated one):

* **orientation** – an object whose z axis lies within `TILT_DEG` of world up is *upright*
  (it stands on `under`, faces up with `on`), within `TILT_DEG` of world down *inverted*
  (stands on `on`); ``(force O up-part)``. ``(base O side)`` is the side whose outward normal
  points most towards the robot (world -x).
* **stacking** – ``(oc stand-part O S)`` and ``(oc up-part S O)`` when O rests on top of S (an
  object or a table slot); the up part of an object with nothing on it and every side part
  are ``air``; the hand is ``(oc in hand air)`` or ``(oc in hand O)`` with
  ``(isGraspFrom O member palm finger1 finger2)``, and the held object stands on air.
* **workspace** – ``(oc in workspace X)`` for each object and member whose world bounding box
  lies in the robot's workspace (within `WORKSPACE_TOL`); slots and spaces by the scene.
* **free spaces** – ``(oc in SPACE air)`` when no object of the space's slot overlaps it by
  more than `SPACE_OVERLAP`; ``(oc in SPACE O)`` when the object standing on that slot lies in
  it (within `SPACE_FIT`); ``(oc side O SPACE)`` / ``(oc opposite SPACE O)`` when O's
  footprint touches the space's side (gap at most `SPACE_GAP`).

Physical situations with no symbol: an object that toppled, fell off the table, lies on the
table outside every slot, rests *inside* another object (containment is not support), rests on
nothing, or rests on such an object, gets **no** atoms of its own (no part, `force`, `base`
or workspace atoms), so no action can pick it, place on it or slide it; whatever it rests on
is marked as occupied by it (``(oc on slot3 mug)``, ``(oc on pan salt)``), so nothing can be
picked from under it or placed there. `Perception.anomalies` says why, per object.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from utamp_gym.contract.state import FLOOR, TABLE, TILT_DEG, Grasp, PhysicalState
from utamp_gym.scene.geometry import NORMALS, OPPOSITE, SIDES, Box
from utamp_gym.scene.model import STANDING_PART, UP_PART, Scene

WORKSPACE_TOL = 0.01  # m, a box this far outside the workspace still lies in it
SPACE_GAP = 0.01  # m, largest gap between a footprint and a space it touches
SPACE_OVERLAP = 0.015  # m, footprints overlapping less than this only touch
SPACE_FIT = 0.02  # m, a footprint sticking out of a space by less than this lies in it
_COS_TILT = math.cos(math.radians(TILT_DEG))
_TO_ROBOT = np.array([-1.0, 0.0, 0.0])


def _atom(*args: str) -> str:
    return "(" + " ".join(args).lower() + ")"


@dataclass(frozen=True)
class Perception:
    """The perceived symbolic state of one physical state.

    `fluent`: ``oc`` and ``isGraspFrom`` atoms; `orientation`: ``force`` and ``base`` atoms
    (static in the domains, but physically they can change: a toppled object loses them);
    `anomalies`: object -> why it has no symbol; `supports`: object -> what it stands on,
    for the objects that have a symbol and are not held; `held`: the object in the hand.
    Atoms are lower-case PDDL text.
    """

    fluent: frozenset[str]
    orientation: frozenset[str]
    anomalies: Mapping[str, str]
    supports: Mapping[str, str]
    held: str | None = None

    @cached_property
    def atoms(self) -> frozenset[str]:
        """Every perceived atom (fluent and orientation)."""
        return self.fluent | self.orientation

    def tower(self, base: str) -> list[str]:
        """Objects standing on `base`, bottom to top (the base excluded)."""
        above = {s: o for o, s in sorted(self.supports.items())}
        out, cur = [], base
        while cur in above and above[cur] not in out:
            cur = above[cur]
            out.append(cur)
        return out


def quat_matrix(q: tuple[float, ...] | np.ndarray) -> np.ndarray:
    """3x3 rotation of a (w, x, y, z) quaternion (normalised here)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def orientation_of(rot: np.ndarray) -> str | None:
    """ "upright", "inverted" or None (toppled) for an object's world rotation."""
    up = float(rot[2, 2])
    return "upright" if up >= _COS_TILT else "inverted" if up <= -_COS_TILT else None


def up_side(rot: np.ndarray) -> str:
    """The side of an object whose outward normal points most upwards."""
    return max(SIDES, key=lambda s: float((rot @ np.asarray(NORMALS[s]))[2]))


def base_side(rot: np.ndarray) -> str:
    """The lateral side whose outward normal points most towards the robot (world -x)."""
    lateral = ("back", "front", "left", "right")
    return max(lateral, key=lambda s: float((rot @ np.asarray(NORMALS[s])) @ _TO_ROBOT))


def world_box(box: Box, rot: np.ndarray, pos: np.ndarray) -> Box:
    """World axis-aligned bounds of an object-frame box."""
    lo, hi = np.asarray(box.min), np.asarray(box.max)
    centre = rot @ ((lo + hi) / 2) + pos
    half = np.abs(rot) @ ((hi - lo) / 2)
    return Box(tuple((centre - half).tolist()), tuple((centre + half).tolist()))


def declared_state(scene: Scene) -> PhysicalState:
    """The physical state a scene declares: its initial poses and stacking, hand empty."""
    poses = {n: (*p.position, *p.quat) for n, p in scene.poses.items()}
    supports = {o.name: o.on for o in scene.objects}
    return PhysicalState(poses, supports, dict.fromkeys(supports, True), None)


class _Perceiver:
    """One `perceive` call: per-object status first, then the atoms (see module docstring)."""

    def __init__(self, scene: Scene, state: PhysicalState) -> None:
        self.scene, self.state = scene, state
        self.slots = {s.name for s in scene.slots}
        self.rot = {n: quat_matrix(state.poses[n][3:7]) for n in scene.object_names}
        self.pos = {n: np.asarray(state.poses[n][:3], dtype=float) for n in scene.object_names}
        self.held: Grasp | None = state.held
        self.anomalies: dict[str, str] = {}
        self._done: set[str] = set()
        for name in scene.object_names:
            self._status(name, ())

    def _status(self, name: str, chain: tuple[str, ...]) -> str | None:
        """Why `name` has no symbol (also recorded in `anomalies`), or None."""
        if name in self._done:
            return self.anomalies.get(name)
        self._done.add(name)
        why = self._why(name, chain)
        if why is not None:
            self.anomalies[name] = why
        return why

    def _why(self, name: str, chain: tuple[str, ...]) -> str | None:
        rot = self.rot[name]
        held = self.held is not None and self.held.obj == name
        if orientation_of(rot) is None:
            where = "in the hand" if held else "over"
            return f"{name} toppled {where}: its {up_side(rot)} side faces up"
        if held:
            return None
        support = self.state.supports.get(name)
        if support == FLOOR:
            return f"{name} fell off the table"
        if support == TABLE:
            return f"{name} lies on the table outside every slot"
        if support is None:
            return f"{name} rests on nothing (it is in the air or on the robot)"
        if support in self.slots:
            return None
        if support not in self.rot:
            return f"{name} rests on an unknown support '{support}'"
        if not self.state.on_top.get(name, False):
            return f"{name} rests inside {support} (containment is not support)"
        if support in chain:
            return f"{name} rests on {support}, which rests on {name}"
        if self._status(support, (*chain, name)) is not None:
            return f"{name} rests on {support}, which has no symbol"
        return None

    # ------------------------------------------------------------------ atoms
    def perception(self) -> Perception:
        scene, state, held = self.scene, self.state, self.held
        fluent: set[str] = set()
        orient: set[str] = set()
        riders: dict[str, list[str]] = {}
        for name in scene.object_names:
            support = state.supports.get(name)
            if support is not None and (held is None or held.obj != name):
                riders.setdefault(support, []).append(name)
        ok = [n for n in scene.object_names if n not in self.anomalies]
        supports: dict[str, str] = {}
        fluent.add(_atom("oc", "in", "hand", held.obj if held else "air"))
        if held is not None and held.obj not in self.anomalies:
            member = f"{held.obj}-{held.member}"
            fluent.add(_atom("isGraspFrom", held.obj, member, held.palm, *_fingers(held)))
        for name in ok:
            rot, orientation = self.rot[name], orientation_of(self.rot[name])
            assert orientation is not None
            stand, up = STANDING_PART[orientation], UP_PART[orientation]
            orient.add(_atom("force", name, up))
            orient.add(_atom("base", name, base_side(rot)))
            is_held = held is not None and held.obj == name
            below = "air" if is_held else str(state.supports[name])
            if not is_held:
                supports[name] = below
            fluent.add(_atom("oc", stand, name, below))
            for other in riders.get(name, []) or ["air"]:
                fluent.add(_atom("oc", up, name, other))
            fluent.update(_atom("oc", s, name, "air") for s in SIDES if s not in (stand, up))
            fluent.update(self._workspace(name))
        for slot in scene.slots:
            orient.add(_atom("force", slot.name, "on"))
            orient.add(_atom("base", slot.name, "back"))
            for other in riders.get(slot.name, []) or ["air"]:
                fluent.add(_atom("oc", "on", slot.name, other))
            region = Box(slot.region.min, (slot.region.max[0], slot.region.max[1], 0.0))
            if scene.workspace.contains_xy(region, tol=1e-6):
                fluent.add(_atom("oc", "in", "workspace", slot.name))
        for space in scene.spaces:
            fluent.update(self._space(space.name, supports))
        return Perception(
            frozenset(fluent),
            frozenset(orient),
            dict(self.anomalies),
            supports,
            held.obj if held else None,
        )

    def _box(self, name: str, member: str | None = None) -> Box:
        t = self.scene.type_of(name)
        box = t.bbox if member is None else t.members[member].box
        return world_box(box, self.rot[name], self.pos[name])

    def _workspace(self, name: str) -> list[str]:
        ws = self.scene.workspace
        out = []
        if ws.contains(self._box(name), tol=WORKSPACE_TOL):
            out.append(_atom("oc", "in", "workspace", name))
        for member in self.scene.type_of(name).members:
            if ws.contains(self._box(name, member), tol=WORKSPACE_TOL):
                out.append(_atom("oc", "in", "workspace", f"{name}-{member}"))
        return out

    def _space(self, name: str, supports: Mapping[str, str]) -> list[str]:
        scene = self.scene
        space = next(s for s in scene.spaces if s.name == name)
        out = [_atom("oc", "on", space.slot, name), _atom("oc", "under", name, space.slot)]
        box = space.box
        if scene.workspace.contains_xy(box, tol=1e-6):
            out.append(_atom("oc", "in", "workspace", name))
        stack = _stack_of(space.slot, supports)
        occupied, inside = False, None
        for obj in stack:
            foot = self._box(obj)
            if box.overlaps_xy(foot, tol=SPACE_OVERLAP):
                occupied = True
                if supports[obj] == space.slot and box.contains_xy(foot, tol=SPACE_FIT):
                    inside = obj
            for side in ("front", "back", "left", "right"):
                if _touches(foot, box, side):
                    out.append(_atom("oc", side, obj, name))
                    out.append(_atom("oc", OPPOSITE[side], name, obj))
        if inside is not None:
            out.append(_atom("oc", "in", name, inside))
        elif not occupied:
            out.append(_atom("oc", "in", name, "air"))
        return out


def _fingers(grasp: Grasp) -> tuple[str, str]:
    return grasp.finger1, grasp.finger2


def _stack_of(slot: str, supports: Mapping[str, str]) -> list[str]:
    """Objects (with a symbol) standing on `slot`, bottom to top."""
    above: dict[str, list[str]] = {}
    for obj, support in supports.items():
        above.setdefault(support, []).append(obj)
    out, todo = [], list(above.get(slot, []))
    while todo:
        cur = todo.pop(0)
        out.append(cur)
        todo.extend(above.get(cur, []))
    return out


def _touches(foot: Box, space: Box, side: str) -> bool:
    """`space` lies beyond `foot`'s `side` within `SPACE_GAP` (small overlaps allowed)."""
    ax = 0 if side in ("front", "back") else 1
    sign = NORMALS[side][ax]
    gap = space.min[ax] - foot.max[ax] if sign > 0 else foot.min[ax] - space.max[ax]
    if not -SPACE_OVERLAP <= gap <= SPACE_GAP:
        return False
    across = 1 - ax
    return foot.min[across] < space.max[across] and space.min[across] < foot.max[across]


def perceive(scene: Scene, state: PhysicalState) -> Perception:
    """The symbolic state of `scene`'s objects in the physical `state` (module docstring)."""
    return _Perceiver(scene, state).perception()


__all__ = [
    "Perception",
    "base_side",
    "declared_state",
    "orientation_of",
    "perceive",
    "quat_matrix",
    "world_box",
]
