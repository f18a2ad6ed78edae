"""Object poses in symbolic grounding: the scene's initial poses moved by the symbolic effects.

Why: the ``object_poses`` observation should mean the same in both groundings, but symbolic
grounding has no simulator, so the poses follow a simple, documented rule per macro action
(orientations never change; every macro action keeps them):

* ``pick-support X ...``: X is in the hand and rises `LIFT_HEIGHT` straight up.
* ``place-support X ... Y ...``: X is centred (by its footprint) on Y's up-facing usable
  surface and rests at its height; on a table slot, it is centred on the slot's position at
  z = 0. This is the rule `Scene.poses` uses for the initial stacks.
* ``slide-support X ... S ...``: X's footprint centre moves to the centre of the free space S,
  carrying whatever stands on it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.scene_cache import SceneCache

LIFT_HEIGHT = 0.25  # m, how high a held object is reported above where it was picked


@dataclass(frozen=True)
class _Geometry:
    """What a scene fixes: initial poses, and per object its footprint centre and bottom and
    its up surface's centre and height (object frame); xy of slots and spaces."""

    pose: np.ndarray
    present: np.ndarray
    foot: dict[str, tuple[float, float, float]]
    surface: dict[str, tuple[float, float, float]]
    places: dict[str, tuple[float, float]]

    @staticmethod
    def of(scene: Scene, rows: dict[str, int]) -> _Geometry:
        pose = np.zeros((len(rows), 7))
        present = np.zeros(len(rows), np.int8)
        foot, surface = {}, {}
        for o in scene.objects:
            p = scene.poses[o.name]
            pose[rows[o.name]] = (*p.position, *p.quat)
            present[rows[o.name]] = 1
            box = scene.oriented_bbox(o.name)
            foot[o.name] = (float(box.center[0]), float(box.center[1]), float(box.min[2]))
            (cx, cy), height = scene.support_surface(o.name, np.zeros(3))
            surface[o.name] = (float(cx), float(cy), float(height))
        places = {s.name: (float(s.position[0]), float(s.position[1]))
                  for s in (*scene.slots, *scene.spaces)}  # fmt: skip
        return _Geometry(pose, present, foot, surface, places)


class SymbolicPoses:
    """Poses ``[x, y, z, qw, qx, qy, qz]`` of the catalogue objects `names` (rows, in order)."""

    def __init__(self, names: Sequence[str]) -> None:
        self.names = tuple(names)
        self._row = {n: i for i, n in enumerate(self.names)}
        self._pose = np.zeros((len(self.names), 7))
        self._present = np.zeros(len(self.names), np.int8)
        self._above: dict[str, str] = {}  # support (object or slot) -> what stands on it
        self._below: dict[str, str] = {}
        self._geometry: _Geometry = _Geometry(self._pose, self._present, {}, {}, {})
        self._cache: SceneCache[_Geometry] = SceneCache()  # resets are frequent

    def reset(self, scene: Scene) -> None:
        """Start from the scene's initial poses and stacking."""
        geometry = self._cache.get(scene.key, lambda: _Geometry.of(scene, self._row))
        self._geometry = geometry
        self._pose = geometry.pose.copy()
        self._present = geometry.present
        self._below = {o.name: o.on for o in scene.objects}
        self._above = {o.on: o.name for o in scene.objects}

    def apply(self, kind: str, obj: str, target: str) -> None:
        """Move objects as macro action `kind` on `obj` (target: support or space) does."""
        pose, r = self._pose, self._row[obj]  # scalar arithmetic: cheaper than tiny arrays
        if kind == "pick-support":
            self._above.pop(self._below.pop(obj, ""), None)
            pose[r, 2] += LIFT_HEIGHT
        elif kind == "place-support":
            if target in self._geometry.places:
                (x, y), z = self._geometry.places[target], 0.0
            else:
                tx, ty, tz = pose[self._row[target], :3].tolist()
                sx, sy, sz = self._geometry.surface[target]
                x, y, z = tx + sx, ty + sy, tz + sz
            fx, fy, fz = self._geometry.foot[obj]
            pose[r, 0], pose[r, 1], pose[r, 2] = x - fx, y - fy, z - fz
            self._below[obj], self._above[target] = target, obj
        elif kind == "slide-support":
            (x, y), (fx, fy, _) = self._geometry.places[target], self._geometry.foot[obj]
            dx, dy = x - (pose[r, 0] + fx), y - (pose[r, 1] + fy)
            cur: str | None = obj
            while cur is not None:
                pose[self._row[cur], :2] += (dx, dy)
                cur = self._above.get(cur)

    def observation(self) -> np.ndarray:
        """A fresh float32 (n, 7) array; absent objects are all zero."""
        return self._pose.astype(np.float32)

    def present(self) -> np.ndarray:
        return self._present.copy()  # the cached array itself is never handed out

    def tower(self, base: str) -> list[str]:
        """Objects standing on `base`, bottom to top (the base itself excluded)."""
        out, cur = [], self._above.get(base)
        while cur is not None:
            out.append(cur)
            cur = self._above.get(cur)
        return out
