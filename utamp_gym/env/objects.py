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
order nor the position of the tray can be memorised. There are `MAX_OBJECTS` slots unless the
env option ``slots`` gives more (other spaces: `n_actions`, `n_entities`; smaller scenes leave
slots empty). Table regions (the scene's table slots,
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

**Names.** The env's ``action_strings[a]`` is `action_text` (a): the index in this vocabulary,
the same in every scene (``pick slot3 member0 grasp on/left/right``, ``place slot3 on
region1``). The PDDL string of the ground action it runs depends on the scene, the slots and
the state: ``env.action_pddl(a)`` gives it before the step and ``info["action"]`` after.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
from gymnasium import spaces

from utamp_gym.env.object_maps import SceneMap, shared_maps, tables
from utamp_gym.env.object_space import (
    _FLUENT_KEYS,
    _K,
    _R,
    _S,
    BOUND,
    GRASPS,
    INTERFACES,
    MAX_MEMBERS,
    MAX_OBJECTS,
    MAX_REGIONS,
    MAX_SLOTS,
    MAX_SPACES,
    N_ACTIONS,
    N_ATTRIBUTES,
    N_ENTITIES,
    OPERATORS,
    ObjectAction,
    TypeSource,
    action_text,
    action_texts,
    declared_type,
    decode,
    encode,
    encode_type,
    member_order,
    n_actions,
    n_entities,
    observation_space,
    slot_count,
)
from utamp_gym.scene.geometry import SIDES
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.universe import Universe, UniverseKey, ground_universe

__all__ = [
    "BOUND", "GRASPS", "INTERFACES", "MAX_MEMBERS", "MAX_OBJECTS", "MAX_REGIONS", "MAX_SLOTS",
    "MAX_SPACES", "N_ACTIONS", "N_ATTRIBUTES", "N_ENTITIES", "OPERATORS", "ObjectAction",
    "ObjectInterface", "TypeSource", "action_text", "action_texts", "declared_type", "decode",
    "encode", "encode_type", "member_order", "n_actions", "n_entities", "observation_space",
    "slot_count",
]  # fmt: skip


class ObjectInterface:
    """Translates between a kitchen env's ground universe and the fixed object-centric spaces
    for one episode at a time (`reset`) with `slots` object slots (default `MAX_OBJECTS`:
    more make other spaces); see the module docstring."""

    def __init__(
        self, universe: Universe, types: TypeSource = declared_type, slots: int = _K
    ) -> None:
        if isinstance(slots, bool) or not isinstance(slots, int) or not 1 <= slots <= MAX_SLOTS:
            raise ValueError(f"slots must be an integer in 1..{MAX_SLOTS}, got {slots!r}")
        self.universe, self.types, self.k = universe, types, slots
        self.n_actions = n_actions(slots)
        self.observation_space = observation_space(slots)
        self.action_space = spaces.Discrete(self.n_actions)
        self._shapes = {k: self.observation_space[k].shape for k in _FLUENT_KEYS}
        sizes = [int(np.prod(s)) for s in self._shapes.values()]
        self._offsets = dict(zip(_FLUENT_KEYS, np.cumsum([0, *sizes[:-1]]).tolist(), strict=True))
        self._size = sum(sizes)
        self._fluent_slices = {  # key -> (start, end, shape) in the flat fluent vector
            k: (self._offsets[k], self._offsets[k] + n, self._shapes[k])
            for k, n in zip(_FLUENT_KEYS, sizes, strict=True)
        }
        self.slots: dict[str, int] = {}  # object name -> slot, this episode
        self._static: dict[str, np.ndarray] = {}
        self._maps = shared_maps(universe.key, slots)  # what does not depend on the slots
        self._up: tuple[frozenset[str], np.ndarray] | None = None

    def __getstate__(self) -> dict[str, object]:
        state = self.__dict__.copy()
        state["universe"] = self.universe.key
        del state["_maps"]  # the process's shared cache, not this interface's
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        key: UniverseKey = state["universe"]  # type: ignore[assignment]
        state["universe"] = ground_universe(key)
        state["_maps"] = shared_maps(key, state.get("k", _K))  # type: ignore[arg-type]
        self.__dict__.update(state)

    # ------------------------------------------------------------------ episode
    def reset(self, scene: Scene, rng: np.random.Generator) -> None:
        """Assign the scene's objects to random slots and map the universe onto them."""
        names = scene.object_names
        limits = {"objects": (len(names), self.k, "MAX_OBJECTS, or the env option slots"),
                  "table slots": (len(scene.slots), _R, "MAX_REGIONS"),
                  "free spaces": (len(scene.spaces), _S, "MAX_SPACES")}  # fmt: skip
        for what, (n, cap, const) in limits.items():
            if n > cap:
                raise ValueError(
                    f"scene '{scene.name}' has {n} {what}; the objects interface has room for "
                    f"{cap} (utamp_gym.env.objects.{const})"
                )
        order = rng.permutation(self.k)[: len(names)]
        self.scene, self.slots = scene, {n: int(s) for n, s in zip(names, order, strict=True)}
        self._up = None  # the up-facing sides of the episode's static atoms (`observation`)

        def scene_map() -> SceneMap:
            return SceneMap.of(tables(self.universe.key), scene, self.types, self._offsets, self.k)

        if self.types is declared_type:  # declared types are fixed per scene
            cached = self._maps.get(scene.key, scene_map)
        else:
            cached = scene_map()
        self._index, self._atom_pos = cached.place(order)
        order_ = np.argsort(self._index, kind="stable")
        self._sorted = order_[self._index[order_] >= 0]
        self._starts = np.searchsorted(self._index[self._sorted], np.arange(self.n_actions + 1))
        self._static_obs(scene, cached.attributes, order)

    def _static_obs(self, scene: Scene, attributes: np.ndarray, slots: np.ndarray) -> None:
        attrs = np.zeros((self.k, N_ATTRIBUTES), np.float32)
        present = np.zeros(self.k, np.int8)
        attrs[slots], present[slots] = attributes, 1
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
        out = np.zeros(self.n_actions, bool)
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
        """`action_text` of an index with this episode's names in brackets (failure reasons):
        ``pick slot0 (mug) member1 (handle) grasp ...``, ``place slot0 (mug) on region1
        (slot2)``; an empty slot is ``(empty)``."""
        a = decode(index, self.k)
        where = {s: n for n, s in self.slots.items()}
        scene = self.scene
        out = []
        for word in action_text(index, self.k).split(" "):
            name = None
            if word.startswith("slot"):
                name = where.get(int(word[4:]), "empty")
            elif word.startswith("member") and a.obj in where:
                order = member_order(scene.type_of(where[a.obj]))
                name = order[a.member] if a.member is not None and a.member < len(order) else "none"
            elif word.startswith("region"):
                r = int(word[6:])
                name = scene.slots[r].name if r < len(scene.slots) else "none"
            elif word.startswith("space"):
                s = int(word[5:])
                name = scene.spaces[s].name if s < len(scene.spaces) else "none"
            out.append(word if name is None else f"{word} ({name})")
        return " ".join(out)

    def fluent_layout(self, atoms: Iterable[str]) -> dict[str, np.ndarray]:
        """The fluent entries (``held``, ``contact``, ...) of a set of universe fluent atoms
        in this episode's slots, e.g. a goal's (atoms outside the universe are left out)."""
        index = self.universe.fluent_index
        flat = np.zeros(self._size, np.int8)
        pos = self._atom_pos[[index[a] for a in atoms if a in index]]
        flat[pos[pos >= 0]] = 1
        return {k: flat[a:b].reshape(shape) for k, (a, b, shape) in self._fluent_slices.items()}

    def observation(
        self, fluent: np.ndarray, static_atoms: frozenset[str], poses: Mapping[str, np.ndarray]
    ) -> dict[str, np.ndarray]:
        """The observation from the state's fluent vector (over the universe), its static
        atoms (for the up-facing sides) and the objects' poses by name."""
        flat = np.zeros(self._size, np.int8)
        pos = self._atom_pos[fluent.astype(bool)]
        flat[pos[pos >= 0]] = 1
        obs = {k: v.copy() for k, v in self._static.items()}
        for k, (start, end, shape) in self._fluent_slices.items():
            obs[k] = flat[start:end].reshape(shape)
        if self._up is None or self._up[0] is not static_atoms:  # new episode or perception
            up = np.zeros((self.k, len(SIDES)), np.int8)
            for atom in static_atoms:
                if atom.startswith("(force "):
                    _, name, side = atom[1:-1].split()
                    if name in self.slots and side in SIDES:
                        up[self.slots[name], SIDES.index(side)] = 1
            self._up = (static_atoms, up)
        obs["up"] = self._up[1].copy()
        p = np.zeros((self.k, 7), np.float32)
        for name, slot in self.slots.items():
            if name in poses:
                p[slot] = poses[name]
        obs["poses"] = p
        return obs
