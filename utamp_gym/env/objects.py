"""The object-centric interface (env option ``interface="objects"``): spaces that do not change
with the object set, so one policy runs on every scene, split and suite.

Why: the grounded interface numbers the ground actions of one suite's universe, so an agent
trained there cannot even be run on an object it has not seen. Here every object of a scene
sits in one of `MAX_OBJECTS` *slots*, described by its attributes, pose and relations, and an
action is a parametrised macro action over slots: one fixed `Discrete` space with an exact
mask, whatever the scene.

**Slots.** At every reset the scene's objects take a uniformly random set and order of slots
(drawn from the env's RNG after everything else the reset draws, so scenes, noise and physics
match the grounded interface's at equal seeds); empty slots are interleaved, so neither the
order nor the position of the tray can be memorised. Table regions (the scene's table slots,
in scene order: they are places, not objects) take `MAX_REGIONS` region indices and free
spaces `MAX_SPACES` space indices. An object's members are indexed body first, then in the
type's declared order (`MAX_MEMBERS`).

**Observation** (``Dict``; E = objects + regions + spaces = `N_ENTITIES` entities, in that order):

* ``present`` (K), ``attributes`` (K, `N_ATTRIBUTES`: `encode_type` of each object's type),
  ``poses`` (K, 7: x, y, z, qw, qx, qy, qz), ``up`` (K, 6: the side facing up, `SIDES`);
* ``regions`` and ``spaces`` (R / S, 5: present, centre x, y, size x, y);
* the fluent U-TAMP-2 state, lossless: ``held`` (K: ``oc in hand o``), ``contact`` (E, E, 7:
  ``oc p a b``, part p of entity a touches b, `PARTS`), ``free`` (E, 7: ``oc p a air``),
  ``in_workspace`` (E) and ``member_in_workspace`` (K, M), ``grasp`` (K, M, 24:
  ``isGraspFrom``, `GRASPS`).

The attributes come from one function, ``types(scene, name) -> ObjectType`` (default
`declared_type`: the catalogue's), so a perception mode can hand in perceived types instead.

**Action** – ``Discrete(n)``, `ObjectAction` fields encoded by `encode` / `decode`:
``pick`` (object, member, grasp: K·M·24), ``place`` (object, support: an object or a
region, K·(K+R); the member and grasp are the held ones) and ``slide`` (object, member,
grasp, space: K·M·24·S). What the rest of a ground action's arguments say (the part an object
rests on, what it is lifted from) follows from the state. `action_masks()` and
``info["action_mask"]`` show an index when one of its ground actions is shown by the env's
mask mode (``affordances``, ``geometric``, ``none``: unchanged meaning); stepping it runs that
ground action (an applicable one first). An index with no ground action in the scene (an
empty slot, a grasp no object has) fails like an unapplicable action: nothing changes and
``info["failure_reason"]`` says why.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from gymnasium import spaces

from utamp_gym.env.universe import Universe, UniverseKey, ground_universe
from utamp_gym.scene.catalogue import GEOMS, MEMBER_KINDS, ROBUSTNESS, SHAPES, ObjectType
from utamp_gym.scene.geometry import PARTS, SIDES, is_adjacent, is_opposite
from utamp_gym.scene.materials import MATERIALS
from utamp_gym.scene.model import Scene

INTERFACES = ("grounded", "objects")
MAX_OBJECTS = 6  # K
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


def encode(action: ObjectAction) -> int:
    """The `Discrete` index of an `ObjectAction`; `ValueError` for a field out of range."""
    op, i, m, g, j, s = action
    ranges = {"pick": (_M, _G, None, None), "place": (None, None, _K + _R, None),
              "slide": (_M, _G, None, _S)}  # fmt: skip
    if op not in ranges or not 0 <= i < _K:
        raise ValueError(f"not an object action: {action!r}")
    for value, n in zip((m, g, j, s), ranges[op], strict=True):
        if (n is None) != (value is None) or (n is not None and not 0 <= value < n):  # type: ignore[operator]
            raise ValueError(f"field out of range in {action!r}")
    if op == "pick":
        return (i * _M + m) * _G + g  # type: ignore[operator]
    if op == "place":
        return _PLACE0 + i * (_K + _R) + j  # type: ignore[operator]
    return _SLIDE0 + ((i * _M + m) * _G + g) * _S + s  # type: ignore[operator]


def decode(index: int) -> ObjectAction:
    """The `ObjectAction` of a `Discrete` index (the inverse of `encode`)."""
    if not 0 <= index < N_ACTIONS:
        raise ValueError(f"action {index} is out of range [0, {N_ACTIONS})")
    if index < _PLACE0:
        (i, m), g = divmod(index // _G, _M), index % _G
        return ObjectAction("pick", i, m, g)
    if index < _SLIDE0:
        i, j = divmod(index - _PLACE0, _K + _R)
        return ObjectAction("place", i, support=j)
    rest, s = divmod(index - _SLIDE0, _S)
    (i, m), g = divmod(rest // _G, _M), rest % _G
    return ObjectAction("slide", i, m, g, space=s)


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


class _Tables(NamedTuple):
    """A universe's actions and fluent atoms, taken apart by symbol (module docstring)."""

    op: np.ndarray  # (n_actions,) operator index
    obj: np.ndarray  # symbol id of the moved object
    member: tuple[str, ...]  # member name (pick, slide)
    grasp: np.ndarray  # grasp index (pick, slide; 0 for place)
    support: np.ndarray  # symbol id of the target (place)
    space: np.ndarray  # symbol id of the space (slide)
    symbols: tuple[str, ...]  # symbol id -> name
    atoms: tuple[tuple[str, ...], ...]  # fluent atom -> (predicate, *args)


@lru_cache(maxsize=16)
def _tables(key: UniverseKey) -> _Tables:
    u = ground_universe(key)
    ids: dict[str, int] = {"": 0}
    sym = lambda name: ids.setdefault(name, len(ids))  # noqa: E731
    ops, objs, members, grasps, supports, spaces_ = [], [], [], [], [], []
    for action in u.actions:
        name, *args = action[1:-1].split()
        obj = args[0]
        ops.append(("pick-support", "place-support", "slide-support").index(name))
        objs.append(sym(obj))
        members.append(args[1][len(obj) + 1 :])
        grasp = _GRASP_INDEX.get((args[2], args[3], args[4]), -1)
        grasps.append(grasp)
        supports.append(sym(args[8]) if name == "place-support" else 0)
        spaces_.append(sym(args[9]) if name == "slide-support" else 0)
    atoms = tuple(tuple(a[1:-1].split()) for a in u.fluent_atoms)
    for a in atoms:
        for name in a[1:]:
            sym(name)
    return _Tables(
        np.array(ops), np.array(objs), tuple(members), np.array(grasps), np.array(supports),
        np.array(spaces_), tuple(ids), atoms,
    )  # fmt: skip


def observation_space() -> spaces.Dict:
    """The (fixed) observation space of the objects interface."""
    k, e = MAX_OBJECTS, N_ENTITIES
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


_FLUENT_KEYS = ("held", "contact", "free", "in_workspace", "member_in_workspace", "grasp")


class ObjectInterface:
    """Translates between a kitchen env's ground universe and the fixed object-centric spaces
    for one episode at a time (`reset`); see the module docstring."""

    def __init__(self, universe: Universe, types: TypeSource = declared_type) -> None:
        self.universe, self.types = universe, types
        self.observation_space = observation_space()
        self.action_space = spaces.Discrete(N_ACTIONS)
        self._shapes = {k: self.observation_space[k].shape for k in _FLUENT_KEYS}
        sizes = [int(np.prod(s)) for s in self._shapes.values()]
        self._offsets = dict(zip(_FLUENT_KEYS, np.cumsum([0, *sizes[:-1]]).tolist(), strict=True))
        self._size = sum(sizes)
        self.slots: dict[str, int] = {}  # object name -> slot, this episode
        self._static: dict[str, np.ndarray] = {}

    def __getstate__(self) -> dict[str, object]:
        state = self.__dict__.copy()
        state["universe"] = self.universe.key
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        state["universe"] = ground_universe(state["universe"])  # type: ignore[arg-type]
        self.__dict__.update(state)

    # ------------------------------------------------------------------ episode
    def reset(self, scene: Scene, rng: np.random.Generator) -> None:
        """Assign the scene's objects to random slots and map the universe onto them."""
        names = scene.object_names
        limits = {"objects": (len(names), _K, "MAX_OBJECTS"),
                  "table slots": (len(scene.slots), _R, "MAX_REGIONS"),
                  "free spaces": (len(scene.spaces), _S, "MAX_SPACES")}  # fmt: skip
        for what, (n, cap, const) in limits.items():
            if n > cap:
                raise ValueError(
                    f"scene '{scene.name}' has {n} {what}; the objects interface has room for "
                    f"{cap} (utamp_gym.env.objects.{const})"
                )
        order = rng.permutation(_K)[: len(names)]
        self.scene, self.slots = scene, {n: int(s) for n, s in zip(names, order, strict=True)}
        t = _tables(self.universe.key)
        entity = np.full(len(t.symbols), -1)  # symbol id -> entity index
        member = np.full(len(t.symbols), -1)  # member symbol id -> member index
        owner = np.full(len(t.symbols), -1)  # member symbol id -> its object's slot
        sid = {s: i for i, s in enumerate(t.symbols)}
        types = {n: self.types(scene, n) for n in names}
        for n, typ in types.items():
            if len(typ.members) > _M:
                raise ValueError(
                    f"object '{n}' of scene '{scene.name}' has {len(typ.members)} members; the "
                    f"objects interface has room for {_M} (utamp_gym.env.objects.MAX_MEMBERS)"
                )
        for n, slot in self.slots.items():
            if n in sid:
                entity[sid[n]] = slot
            for k, m in enumerate(member_order(types[n])):
                if f"{n}-{m}" in sid:
                    member[sid[f"{n}-{m}"]], owner[sid[f"{n}-{m}"]] = k, slot
        for r, region in enumerate(scene.slots):
            if region.name in sid:
                entity[sid[region.name]] = _K + r
        for s, space in enumerate(scene.spaces):
            if space.name in sid:
                entity[sid[space.name]] = _K + _R + s
        self._index = self._action_index(t, types, entity)
        order_ = np.argsort(self._index, kind="stable")
        self._sorted = order_[self._index[order_] >= 0]
        self._starts = np.searchsorted(self._index[self._sorted], np.arange(N_ACTIONS + 1))
        self._atom_pos = self._atom_positions(t, entity, member, owner)
        self._static_obs(scene, types)

    def _action_index(
        self, t: _Tables, types: Mapping[str, ObjectType], entity: np.ndarray
    ) -> np.ndarray:
        """Per universe action, its index in this episode (-1: not in this scene)."""
        slot = entity[t.obj]
        ok = (slot >= 0) & (slot < _K) & (t.grasp >= 0)
        midx = np.array([
            member_order(types[t.symbols[o]]).index(m)
            if o_ok and m in types[t.symbols[o]].members else -1
            for o, m, o_ok in zip(t.obj, t.member, ok, strict=True)
        ])  # fmt: skip
        support, space = entity[t.support], entity[t.space] - _K - _R
        pick = (slot * _M + midx) * _G + t.grasp
        place = _PLACE0 + slot * (_K + _R) + support
        slide = _SLIDE0 + ((slot * _M + midx) * _G + t.grasp) * _S + space
        index = np.choose(t.op, [pick, place, slide])
        valid = ok & np.choose(
            t.op, [(midx >= 0) & (midx < _M), (support >= 0) & (support < _K + _R),
                   (midx >= 0) & (midx < _M) & (space >= 0)]
        )  # fmt: skip
        return np.where(valid, index, -1)

    def _atom_positions(
        self, t: _Tables, entity: np.ndarray, member: np.ndarray, owner: np.ndarray
    ) -> np.ndarray:
        """Per fluent atom, its flat position in the fluent observation (-1: none)."""
        sid = {s: i for i, s in enumerate(t.symbols)}
        part = {p: i for i, p in enumerate(PARTS)}
        off, e = self._offsets, N_ENTITIES
        out = np.full(len(t.atoms), -1)
        for j, (pred, *args) in enumerate(t.atoms):
            if pred == "isgraspfrom":
                o, m, g = (
                    entity[sid[args[0]]],
                    member[sid[args[1]]],
                    _GRASP_INDEX.get(tuple(args[2:])),
                )
                if o >= 0 and m >= 0 and g is not None:
                    out[j] = off["grasp"] + (o * _M + m) * _G + g
                continue
            p, a, b = args
            ea, eb = entity[sid[a]], entity[sid[b]]
            if a == "hand":
                if eb >= 0:
                    out[j] = off["held"] + eb
            elif a == "workspace":
                if eb >= 0:
                    out[j] = off["in_workspace"] + eb
                elif member[sid[b]] >= 0:
                    out[j] = off["member_in_workspace"] + owner[sid[b]] * _M + member[sid[b]]
            elif ea >= 0 and b == "air":
                out[j] = off["free"] + ea * len(PARTS) + part[p]
            elif ea >= 0 and eb >= 0:
                out[j] = off["contact"] + (ea * e + eb) * len(PARTS) + part[p]
        return out

    def _static_obs(self, scene: Scene, types: Mapping[str, ObjectType]) -> None:
        attrs = np.zeros((_K, N_ATTRIBUTES), np.float32)
        present = np.zeros(_K, np.int8)
        for n, slot in self.slots.items():
            attrs[slot], present[slot] = encode_type(types[n]), 1
        regions = np.zeros((_R, 5), np.float32)
        for r, region in enumerate(scene.slots):
            (x0, y0, _), (x1, y1, _) = region.region
            regions[r] = (1.0, *region.position, x1 - x0, y1 - y0)
        free = np.zeros((_S, 5), np.float32)
        for s, space in enumerate(scene.spaces):
            free[s] = (1.0, *space.position, *space.size)
        self._static = {"present": present, "attributes": attrs, "regions": regions,
                        "spaces": free}  # fmt: skip

    # ------------------------------------------------------------------ per step
    def mask(self, ground_mask: np.ndarray) -> np.ndarray:
        """The object-centric mask: an index is shown if one of its ground actions is."""
        out = np.zeros(N_ACTIONS, bool)
        shown = self._index[ground_mask]
        out[shown[shown >= 0]] = True
        return out

    def index_of(self, ground: int) -> int:
        """The index of universe action `ground` in this episode (-1: not in this scene)."""
        return int(self._index[ground])

    def ground_actions(self, index: int) -> np.ndarray:
        """The universe ids of index `index` in this episode (often one; none if absent)."""
        return self._sorted[self._starts[index] : self._starts[index + 1]]

    def resolve(self, index: int, shown: np.ndarray, applicable: np.ndarray) -> int | None:
        """The ground action to run for `index`: shown and applicable, else shown, else the
        first; None if the index has no ground action in this scene."""
        ids = self.ground_actions(index)
        if not ids.size:
            return None
        for want in (shown[ids] & applicable[ids], shown[ids]):
            if want.any():
                return int(ids[np.argmax(want)])
        return int(ids[0])

    def describe(self, index: int) -> str:
        """A readable name of an index (for failure reasons)."""
        a = decode(index)
        where = {s: n for n, s in self.slots.items()}
        parts = [f"{a.operator} slot {a.obj} ({where.get(a.obj, 'empty')})"]
        if a.member is not None:
            parts.append(f"member {a.member}, grasp {'/'.join(GRASPS[a.grasp or 0])}")
        if a.support is not None:
            parts.append(f"onto {'slot' if a.support < _K else 'region'} "
                         f"{a.support if a.support < _K else a.support - _K}")  # fmt: skip
        if a.space is not None:
            parts.append(f"into space {a.space}")
        return ", ".join(parts)

    def observation(
        self, fluent: np.ndarray, static_atoms: frozenset[str], poses: Mapping[str, np.ndarray]
    ) -> dict[str, np.ndarray]:
        """The observation from the state's fluent vector (over the universe), its static
        atoms (for the up-facing sides) and the objects' poses by name."""
        flat = np.zeros(self._size, np.int8)
        pos = self._atom_pos[fluent.astype(bool)]
        flat[pos[pos >= 0]] = 1
        obs = {k: v.copy() for k, v in self._static.items()}
        for k in _FLUENT_KEYS:
            n = int(np.prod(self._shapes[k]))
            obs[k] = flat[self._offsets[k] : self._offsets[k] + n].reshape(self._shapes[k])
        up = np.zeros((_K, len(SIDES)), np.int8)
        for atom in static_atoms:
            if atom.startswith("(force "):
                _, name, side = atom[1:-1].split()
                if name in self.slots and side in SIDES:
                    up[self.slots[name], SIDES.index(side)] = 1
        obs["up"] = up
        p = np.zeros((_K, 7), np.float32)
        for name, slot in self.slots.items():
            if name in poses:
                p[slot] = poses[name]
        obs["poses"] = p
        return obs
