"""The fixed vocabulary of the object-centric interface: slots, action indices, attributes.

What an index or an observation entry *means*, whatever the scene (`utamp_gym.env.objects` maps
a scene's ground actions and atoms onto it): the limits (`MAX_OBJECTS`, `MAX_MEMBERS`,
`MAX_REGIONS`, `MAX_SPACES`), the 24 `GRASPS`, `ObjectAction` and its `encode` / `decode` (and
`action_text`, its readable name), the attribute vector of a type (`encode_type`) and the
observation space. The object slots are `MAX_OBJECTS` unless an env asks for more (option
``slots``): every function of a slot count takes it as ``k``.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from gymnasium import spaces

from utamp_gym.scene.catalogue import GEOMS, MEMBER_KINDS, ROBUSTNESS, SHAPES, ObjectType
from utamp_gym.scene.geometry import PARTS, SIDES, is_adjacent, is_opposite
from utamp_gym.scene.materials import MATERIALS
from utamp_gym.scene.model import Scene

#: the env option ``interface``: the suite's ground actions and atoms, or object slots
INTERFACES = ("grounded", "objects")
#: K: the default object slots (`UTampKitchenProcedural-v0`'s spaces); an env's option
#: ``slots`` may give more (`ObjectInterface`), up to `MAX_SLOTS`
MAX_OBJECTS = 6
MAX_SLOTS = 16
MAX_MEMBERS = 6  # M
MAX_REGIONS = 8  # R: table slots
MAX_SPACES = 2  # S: free spaces to slide into
N_ENTITIES = MAX_OBJECTS + MAX_REGIONS + MAX_SPACES
#: (palm, finger 1, finger 2): the palm on one side, the fingers on an opposite pair beside it
GRASPS: tuple[tuple[str, str, str], ...] = tuple(
    (p, f1, f2)
    for p in SIDES
    for f1 in SIDES
    for f2 in SIDES
    if is_adjacent(p, f1) and is_opposite(f1, f2)
)
OPERATORS = ("pick", "place", "slide")
_GRASP_INDEX = {g: i for i, g in enumerate(GRASPS)}
_K, _M, _G, _R, _S = MAX_OBJECTS, MAX_MEMBERS, len(GRASPS), MAX_REGIONS, MAX_SPACES
_PLACE0 = _K * _M * _G
_SLIDE0 = _PLACE0 + _K * (_K + _R)
N_ACTIONS = _SLIDE0 + _K * _M * _G * _S
_MATERIALS = (*MATERIALS, "other")
#: per member: present, kind, geom, box min (3) and max (3)
_MEMBER_WIDTH = 1 + len(MEMBER_KINDS) + len(GEOMS) + 6
#: per side: shape, usable size (2), surface height, food surface
_PART_WIDTH = len(SHAPES) + 4
N_ATTRIBUTES = 1 + len(_MATERIALS) + len(ROBUSTNESS) + 1 + 6 + 6 * _PART_WIDTH + _M * _MEMBER_WIDTH
TypeSource = Callable[[Scene, str], ObjectType]
#: bound of the Box entries (metres, kilograms: masses go up to 1000 kg)
BOUND = 1000.0


class ObjectAction(NamedTuple):
    """One index of the action space; fields an operator does not choose are None."""

    operator: str  # pick | place | slide
    obj: int  # object slot
    member: int | None = None  # member index (pick, slide)
    grasp: int | None = None  # index into GRASPS (pick, slide)
    support: int | None = None  # place: an object slot < K, or K + region index
    space: int | None = None  # slide: space index


def n_entities(k: int = MAX_OBJECTS) -> int:
    """Entities of an interface with `k` object slots: objects, table regions, free spaces."""
    return k + _R + _S


def n_actions(k: int = MAX_OBJECTS) -> int:
    """Indices of the action space of an interface with `k` object slots (`N_ACTIONS` at
    the default `MAX_OBJECTS`)."""
    return k * _M * _G + k * (k + _R) + k * _M * _G * _S


def slots_for_actions(n: int) -> int | None:
    """The object slots `k` (1..`MAX_SLOTS`) whose action space has `n` indices (None if no
    slot count has): the slots of a model saved with only its action-space size."""
    return next((k for k in range(1, MAX_SLOTS + 1) if n_actions(k) == n), None)


def encode(action: ObjectAction, k: int = MAX_OBJECTS) -> int:
    """The `Discrete` index of an `ObjectAction` (`k` object slots); `ValueError` for a field
    out of range."""
    op, i, m, g, j, s = action
    ranges = {"pick": (_M, _G, None, None), "place": (None, None, k + _R, None),
              "slide": (_M, _G, None, _S)}  # fmt: skip
    if op not in ranges or not 0 <= i < k:
        raise ValueError(f"not an object action: {action!r}")
    for value, n in zip((m, g, j, s), ranges[op], strict=True):
        if (n is None) != (value is None) or (n is not None and not 0 <= value < n):  # type: ignore[operator]
            raise ValueError(f"field out of range in {action!r}")
    place0 = k * _M * _G
    if op == "pick":
        return (i * _M + m) * _G + g  # type: ignore[operator]
    if op == "place":
        return place0 + i * (k + _R) + j  # type: ignore[operator]
    return place0 + k * (k + _R) + ((i * _M + m) * _G + g) * _S + s  # type: ignore[operator]


def decode(index: int, k: int = MAX_OBJECTS) -> ObjectAction:
    """The `ObjectAction` of a `Discrete` index (the inverse of `encode`; `k` object slots)."""
    n = n_actions(k)
    if not 0 <= index < n:
        raise ValueError(f"action {index} is out of range [0, {n})")
    place0 = k * _M * _G
    slide0 = place0 + k * (k + _R)
    if index < place0:
        (i, m), g = divmod(index // _G, _M), index % _G
        return ObjectAction("pick", i, m, g)
    if index < slide0:
        i, j = divmod(index - place0, k + _R)
        return ObjectAction("place", i, support=j)
    rest, s = divmod(index - slide0, _S)
    (i, m), g = divmod(rest // _G, _M), rest % _G
    return ObjectAction("slide", i, m, g, space=s)


def action_text(index: int, k: int = MAX_OBJECTS) -> str:
    """What index `index` does, in the interface's own vocabulary and the same in every scene:
    ``pick slot3 member1 grasp on/left/right``, ``place slot3 on slot1`` (an object slot) or
    ``place slot3 on region2`` (a table region), ``slide slot0 member0 grasp on/left/right to
    space1``. The grasp is (palm, finger 1, finger 2), `GRASPS`; `k`: the object slots."""
    a = decode(index, k)
    text = f"{a.operator} slot{a.obj}"
    if a.member is not None:
        text += f" member{a.member} grasp {'/'.join(GRASPS[a.grasp or 0])}"
    if a.support is not None:
        text += f" on slot{a.support}" if a.support < k else f" on region{a.support - k}"
    if a.space is not None:
        text += f" to space{a.space}"
    return text


@lru_cache(maxsize=4)
def action_texts(k: int = MAX_OBJECTS) -> tuple[str, ...]:
    """`action_text` of every index, in index order (the objects env's ``action_strings``)."""
    return tuple(action_text(i, k) for i in range(n_actions(k)))


def declared_type(scene: Scene, name: str) -> ObjectType:
    """The default attribute source: the object's catalogue type as the scene declares it."""
    return scene.type_of(name)


def member_order(t: ObjectType) -> tuple[str, ...]:
    """Member names in slot order: the body first, then the type's declared order."""
    return (t.body.name, *(m for m in t.members if m != t.body.name))


def encode_type(t: ObjectType) -> np.ndarray:
    """Fixed-size float32 attributes of a type (`N_ATTRIBUTES`): mass (kg), material,
    robustness, movable, bounding-box size and centre, per side its shape, usable size,
    surface height and food flag, per member its kind, geometry and box (object frame, m)."""
    out: list[float] = [t.mass]
    out += [float(t.material == m) for m in _MATERIALS[:-1]]
    out.append(float(t.material not in MATERIALS))
    out += [float(t.robustness == r) for r in ROBUSTNESS]
    out.append(float(t.movable))
    box = t.bbox
    out += [float(v) for v in box.size] + [float(v) for v in box.center]
    for side in SIDES:
        attrs = t.parts[side]
        out += [float(attrs.shape == s) for s in SHAPES]
        out += [*map(float, t.surface_size(side)), float(t.surface_height(side))]
        out.append(float(attrs.food_surface))
    names = member_order(t)
    for k in range(_M):
        if k >= len(names):
            out += [0.0] * _MEMBER_WIDTH
            continue
        m = t.members[names[k]]
        out += [1.0, *(float(m.kind == kind) for kind in MEMBER_KINDS)]
        out += [float(m.geom == g) for g in GEOMS] + [*m.box.min, *m.box.max]
    return np.asarray(out, np.float32)


def observation_space(k: int = MAX_OBJECTS) -> spaces.Dict:
    """The (fixed) observation space of the objects interface with `k` object slots."""
    e = n_entities(k)
    box = lambda *shape: spaces.Box(-BOUND, BOUND, shape, np.float32)  # noqa: E731
    return spaces.Dict({
        "present": spaces.MultiBinary(k), "attributes": box(k, N_ATTRIBUTES),
        "poses": box(k, 7), "up": spaces.MultiBinary((k, len(SIDES))),
        "regions": box(MAX_REGIONS, 5), "spaces": box(MAX_SPACES, 5),
        "held": spaces.MultiBinary(k), "contact": spaces.MultiBinary((e, e, len(PARTS))),
        "free": spaces.MultiBinary((e, len(PARTS))), "in_workspace": spaces.MultiBinary(e),
        "member_in_workspace": spaces.MultiBinary((k, MAX_MEMBERS)),
        "grasp": spaces.MultiBinary((k, MAX_MEMBERS, len(GRASPS))),
    })  # fmt: skip


def slot_count(space: spaces.Dict) -> int:
    """The object slots of an objects-interface observation space (its ``present`` entry)."""
    return int(space["present"].shape[0])


_FLUENT_KEYS = ("held", "contact", "free", "in_workspace", "member_in_workspace", "grasp")
