"""The scene model: the one source of truth for symbols, physics, envs and evaluation.

A scene names the objects present, what each initially stands on (a table slot or
another object), the table's slots, free spaces for sliding and the robot's
reachable workspace. Poses follow from the data: objects are axis-aligned with the
table and stand at the centroid of their support; an `inverted` object is turned a
half turn about its x axis. A scene may carry its goal (`utamp_gym.tasks.goal.Goal`);
without one the goal is the paper's tower on `Scene.tower_base`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from functools import cached_property
from typing import Any, NamedTuple

from utamp_gym.errors import SceneError, UnknownNameError
from utamp_gym.scene.catalogue import Catalogue, ObjectType
from utamp_gym.scene.geometry import Box
from utamp_gym.tasks.goal import Goal

ORIENTATIONS = ("upright", "inverted")
#: quaternion (w, x, y, z) of each orientation
ORIENTATION_QUAT: dict[str, tuple[float, float, float, float]] = {
    "upright": (1.0, 0.0, 0.0, 0.0),
    "inverted": (0.0, 1.0, 0.0, 0.0),
}
#: the part an object stands on / faces up with, per orientation
STANDING_PART = {"upright": "under", "inverted": "on"}
UP_PART = {"upright": "on", "inverted": "under"}


class Slot(NamedTuple):
    """A region of the table top where a stack may stand; stacks stand at `position`."""

    name: str
    position: tuple[float, float]
    region: Box

    @property
    def box(self) -> Box:
        return self.region


class Space(NamedTuple):
    """A free region inside a slot into which an object may be slid."""

    name: str
    slot: str
    position: tuple[float, float]
    size: tuple[float, float]

    @property
    def box(self) -> Box:
        (cx, cy), (hx, hy) = self.position, (self.size[0] / 2, self.size[1] / 2)
        return Box((cx - hx, cy - hy, 0.0), (cx + hx, cy + hy, 0.0))


class SceneObject(NamedTuple):
    """An object instance: its type, its initial support and orientation."""

    name: str
    type: str
    on: str
    orientation: str = "upright"
    position: tuple[float, float] | None = None


class Pose(NamedTuple):
    """Position (m) and orientation quaternion (w, x, y, z) in the world frame."""

    position: tuple[float, float, float]
    quat: tuple[float, float, float, float]


class Scene:
    """A kitchen-table scene. Build with `load_scene` or `scene_from_dict` (they validate).

    Immutable; equal when all fields are; `_replace` returns a copy with some fields changed.
    """

    _FIELDS = (
        "name",
        "catalogue",
        "table_type",
        "workspace",
        "slots",
        "spaces",
        "objects",
        "custom_types",
        "description",
        "source",
        "goal_base",
        "goal",
    )
    name: str
    catalogue: Catalogue
    table_type: str
    workspace: Box
    slots: tuple[Slot, ...]
    spaces: tuple[Space, ...]
    objects: tuple[SceneObject, ...]
    custom_types: Mapping[str, ObjectType]
    description: str
    source: str
    goal_base: str | None
    goal: Goal | None

    def __init__(
        self,
        name: str,
        catalogue: Catalogue,
        table_type: str,
        workspace: Box,
        slots: tuple[Slot, ...],
        spaces: tuple[Space, ...],
        objects: tuple[SceneObject, ...],
        custom_types: Mapping[str, ObjectType] | None = None,
        description: str = "",
        source: str = "<scene>",
        goal_base: str | None = None,
        goal: Goal | None = None,
    ) -> None:
        # the instance dict holds the fields and what `cached_property` computes
        self.__dict__.update(
            name=name,
            catalogue=catalogue,
            table_type=table_type,
            workspace=workspace,
            slots=slots,
            spaces=spaces,
            objects=objects,
            custom_types={} if custom_types is None else custom_types,
            description=description,
            source=source,
            goal_base=goal_base,
            goal=goal,
        )

    def _fields(self) -> tuple[Any, ...]:
        return tuple(self.__dict__[f] for f in Scene._FIELDS)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"cannot assign to field {name!r}: a Scene is immutable")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"cannot delete field {name!r}: a Scene is immutable")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scene) and self._fields() == other._fields()

    __hash__ = None  # type: ignore[assignment]  # its catalogue is not hashable

    def __repr__(self) -> str:
        return f"Scene({', '.join(f'{f}={self.__dict__[f]!r}' for f in Scene._FIELDS)})"

    def __reduce__(self) -> tuple[type[Scene], tuple[Any, ...]]:
        return Scene, self._fields()

    def _replace(self, **changes: Any) -> Scene:
        """A copy with the fields in `changes` replaced (as on the named tuples)."""
        return Scene(**{f: changes.pop(f, self.__dict__[f]) for f in Scene._FIELDS}, **changes)

    @cached_property
    def key(self) -> str:
        """What per-scene caches key the scene by: its name and a digest of its content (every
        field), computed once. A scene built in code may share a packaged scene's name; it
        never shares its key (unless every field is equal)."""
        digest = hashlib.sha256(repr(self).encode()).hexdigest()[:16]
        return f"{self.name}#{digest}"

    @cached_property
    def tower_base(self) -> str:
        """The object the goal tower stands on: `goal_base`, else the scene's wooden tray
        (computed once: an env asks on every step)."""
        if self.goal_base is not None:
            return self.goal_base
        trays = [o.name for o in self.objects if o.type == "wooden-tray"]
        if len(trays) != 1:
            raise SceneError(
                f"set 'goal_base' (the object to stack everything on): the scene has "
                f"{len(trays)} wooden trays; valid: {', '.join(self.object_names)}",
                file=self.source,
                field="goal_base",
            )
        return trays[0]

    # ----------------------------------------------------------------- lookup
    def object(self, name: str) -> SceneObject:
        for o in self.objects:
            if o.name == name:
                return o
        raise UnknownNameError("object", name, self.object_names)

    @cached_property
    def object_names(self) -> tuple[str, ...]:
        """The objects' names in order (computed once: every env step's info lists them)."""
        return tuple(o.name for o in self.objects)

    def type_of(self, name: str) -> ObjectType:
        return self.catalogue[self.object(name).type]

    def slot(self, name: str) -> Slot:
        for s in self.slots:
            if s.name == name:
                return s
        raise UnknownNameError("slot", name, [s.name for s in self.slots])

    @property
    def table(self) -> ObjectType:
        return self.catalogue[self.table_type]

    @property
    def n_objects(self) -> int:
        return len(self.objects)

    # ----------------------------------------------------------------- stacks
    @cached_property
    def stacks(self) -> dict[str, tuple[str, ...]]:
        """Slot name -> object names standing there, bottom to top."""
        above = {o.on: o.name for o in self.objects}
        out: dict[str, tuple[str, ...]] = {}
        for s in self.slots:
            chain, cur = [], s.name
            while cur in above:
                cur = above[cur]
                chain.append(cur)
            if chain:
                out[s.name] = tuple(chain)
        return out

    def slot_of(self, name: str) -> str:
        for slot, chain in self.stacks.items():
            if name in chain:
                return slot
        raise UnknownNameError("object", name, self.object_names)

    def support_of(self, name: str) -> str:
        return self.object(name).on

    # ----------------------------------------------------------------- poses
    def oriented_bbox(self, name: str) -> Box:
        """The object's bounding box in its own frame after applying its orientation."""
        box = self.type_of(name).bbox
        return box.flipped() if self.object(name).orientation == "inverted" else box

    def support_surface(
        self, name: str, origin: Sequence[float]
    ) -> tuple[tuple[float, float], float]:
        """World xy centre and height of the up-facing surface of `name` with origin `origin`."""
        t, inverted = self.type_of(name), self.object(name).orientation == "inverted"
        part = UP_PART[self.object(name).orientation]
        cx, cy = t.surface_center(part)
        h = t.surface_height(part)
        centre = (origin[0] + cx, origin[1] + (-cy if inverted else cy))
        return centre, float(origin[2] - h if inverted else origin[2] + h)

    @cached_property
    def poses(self) -> dict[str, Pose]:
        """Initial pose of every object (frame origin), derived from the stacking.

        A stack's bottom object is centred (by its footprint) on the slot position, or on
        its own `position`; each object above is centred on its support's usable surface
        and rests at that surface's height: "place at the support's centroid".
        """
        out: dict[str, Pose] = {}
        for slot_name, chain in self.stacks.items():
            bottom = self.object(chain[0])
            cx, cy = (
                bottom.position if bottom.position is not None else self.slot(slot_name).position
            )
            centre, z = (float(cx), float(cy)), 0.0
            for name in chain:
                box = self.oriented_bbox(name)
                bx, by = box.center_xy
                origin = (centre[0] - bx, centre[1] - by, z - box.min[2])
                out[name] = Pose(
                    (float(origin[0]), float(origin[1]), float(origin[2])),
                    ORIENTATION_QUAT[self.object(name).orientation],
                )
                centre, z = self.support_surface(name, origin)
        return out

    def world_box(self, name: str, member: str | None = None) -> Box:
        """World-frame box of an object (or one of its members) at its initial pose."""
        t = self.type_of(name)
        box = t.bbox if member is None else t.members[member].box
        if self.object(name).orientation == "inverted":
            box = box.flipped()
        return box.translated(self.poses[name].position)

    def in_workspace(self, box: Box) -> bool:
        return self.workspace.contains(box, tol=1e-6)


class BuiltScene:
    """A scene built in code as a hashable reference (a `Scene` itself is unhashable): equal
    and hashed by its content (`Scene.key`), so an action universe's key
    (`utamp_gym.symbolic.universe.UniverseKey`) can hold it; it pickles with its scene."""

    __slots__ = ("scene",)

    def __init__(self, scene: Scene) -> None:
        self.scene = scene

    def __eq__(self, other: object) -> bool:
        return isinstance(other, BuiltScene) and other.scene.key == self.scene.key

    def __hash__(self) -> int:
        return hash(self.scene.key)

    def __repr__(self) -> str:
        return f"BuiltScene({self.scene.key!r})"

    def __reduce__(self) -> tuple[type[BuiltScene], tuple[Scene]]:
        return BuiltScene, (self.scene,)


__all__ = [
    "ORIENTATIONS",
    "ORIENTATION_QUAT",
    "STANDING_PART",
    "UP_PART",
    "BuiltScene",
    "Pose",
    "Scene",
    "SceneObject",
    "Slot",
    "Space",
]
