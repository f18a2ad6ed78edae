"""The object-centric interface's tables (`utamp_gym.env.objects`): a universe's actions and
fluent atoms taken apart by symbol (`tables`), and each scene's actions and atoms in terms of
its objects' local indices (`SceneMap`), so that a reset only places the objects in slots.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from utamp_gym.env.object_space import (
    _G,
    _GRASP_INDEX,
    _K,
    _M,
    _R,
    _S,
    TypeSource,
    encode_type,
    member_order,
    n_entities,
)
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import PARTS
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.scene_cache import SceneCache
from utamp_gym.symbolic.universe import MOVES_LIKE, UniverseKey, ground_universe

__all__ = ["SceneMap", "Tables", "shared_maps", "tables"]


class Tables(NamedTuple):
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
def tables(key: UniverseKey) -> Tables:
    u = ground_universe(key)
    ids: dict[str, int] = {"": 0}
    sym = lambda name: ids.setdefault(name, len(ids))  # noqa: E731
    ops, objs, members, grasps, supports, spaces_ = [], [], [], [], [], []
    for action in u.actions:
        name, *args = action[1:-1].split()
        name = MOVES_LIKE.get(name, name)  # the extended domain's edge actions: a pick, a place
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
    return Tables(
        np.array(ops), np.array(objs), tuple(members), np.array(grasps), np.array(supports),
        np.array(spaces_), tuple(ids), atoms,
    )  # fmt: skip


class SceneMap(NamedTuple):
    """A scene's actions and atoms in terms of its objects' local indices (scene order), so
    that a reset only has to place the objects in their slots (`place`, vectorised)."""

    types: dict[str, ObjectType]
    attributes: np.ndarray  # (n objects, N_ATTRIBUTES): `encode_type` in scene order
    op: np.ndarray  # per universe action: operator
    obj: np.ndarray  # local index of the moved object (-1: not in the scene)
    member: np.ndarray  # member index (-1: none)
    grasp: np.ndarray  # grasp index (-1: not one of GRASPS)
    support_obj: np.ndarray  # place: local index of the supporting object, else -1
    support_fixed: np.ndarray  # place: K + region index of a table region, else -1
    space: np.ndarray  # slide: space index, else -1
    kind: np.ndarray  # per fluent atom: which observation entry (-1: none), see `place`
    a_obj: np.ndarray  # its first entity: local object index, or -1
    a_fixed: np.ndarray  # ... or a fixed entity (region, space), or -1
    b_obj: np.ndarray  # its second entity (or the grasping object)
    b_fixed: np.ndarray
    extra: np.ndarray  # part index, member index or grasp index, by kind
    extra2: np.ndarray  # grasp atoms: the grasp index
    offsets: Mapping[str, int]
    k: int  # object slots

    @staticmethod
    def of(
        t: Tables, scene: Scene, source: TypeSource, offsets: Mapping[str, int], slots: int = _K
    ) -> SceneMap:
        names = scene.object_names
        types = {n: source(scene, n) for n in names}
        for n, typ in types.items():
            if len(typ.members) > _M:
                raise ValueError(
                    f"object '{n}' of scene '{scene.name}' has {len(typ.members)} members; the "
                    f"objects interface has room for {_M} (utamp_gym.env.objects.MAX_MEMBERS)"
                )
        n_sym = len(t.symbols)
        sid = {s: i for i, s in enumerate(t.symbols)}
        loc, fixed = np.full(n_sym, -1), np.full(n_sym, -1)
        member, owner = np.full(n_sym, -1), np.full(n_sym, -1)
        for i, n in enumerate(names):
            if n in sid:
                loc[sid[n]] = i
            for k, m in enumerate(member_order(types[n])):
                if f"{n}-{m}" in sid:
                    member[sid[f"{n}-{m}"]], owner[sid[f"{n}-{m}"]] = k, i
        for r, region in enumerate(scene.slots):
            if region.name in sid:
                fixed[sid[region.name]] = slots + r
        for s, space in enumerate(scene.spaces):
            if space.name in sid:
                fixed[sid[space.name]] = slots + _R + s
        slot_of = {  # per moved object of the scene: member name -> member index
            o: {m: k for k, m in enumerate(member_order(typ)) if m in typ.members}
            for o in set(t.obj.tolist())
            if loc[o] >= 0 and (typ := types[t.symbols[o]]) is not None
        }
        midx = np.full(len(t.obj), -1)
        moved = np.flatnonzero(loc[t.obj] >= 0)  # the actions of this scene's objects
        owners = t.obj[moved].tolist()
        midx[moved] = [
            slot_of[o].get(t.member[i], -1) for i, o in zip(moved.tolist(), owners, strict=True)
        ]
        space = np.where(fixed[t.space] >= slots + _R, fixed[t.space] - slots - _R, -1)
        part = {p: i for i, p in enumerate(PARTS)}
        n_atoms = len(t.atoms)
        kind, a_obj, a_fixed = np.full(n_atoms, -1), np.full(n_atoms, -1), np.full(n_atoms, -1)
        b_obj, b_fixed = np.full(n_atoms, -1), np.full(n_atoms, -1)
        extra, extra2 = np.zeros(n_atoms, int), np.zeros(n_atoms, int)
        for j, (pred, *args) in enumerate(t.atoms):
            if pred == "isgraspfrom":
                g = _GRASP_INDEX.get(tuple(args[2:]))
                o, m = sid[args[0]], sid[args[1]]
                if loc[o] >= 0 and member[m] >= 0 and g is not None:
                    kind[j], a_obj[j], extra[j], extra2[j] = 5, loc[o], member[m], g
                continue
            p, a, b = args
            ia, ib = sid[a], sid[b]
            if a == "hand":
                kind[j], b_obj[j] = 0, loc[ib]
            elif a == "workspace" and (loc[ib] >= 0 or fixed[ib] >= 0):
                kind[j], b_obj[j], b_fixed[j] = 1, loc[ib], fixed[ib]
            elif a == "workspace" and member[ib] >= 0:
                kind[j], a_obj[j], extra[j] = 2, owner[ib], member[ib]
            elif b == "air":
                kind[j], a_obj[j], a_fixed[j], extra[j] = 3, loc[ia], fixed[ia], part[p]
            else:
                kind[j], a_obj[j], a_fixed[j], extra[j] = 4, loc[ia], fixed[ia], part[p]
                b_obj[j], b_fixed[j] = loc[ib], fixed[ib]
        attributes = np.array([encode_type(types[n]) for n in names], np.float32)
        return SceneMap(
            types, attributes, t.op, loc[t.obj], midx, t.grasp, loc[t.support],
            fixed[t.support], space, kind, a_obj, a_fixed, b_obj, b_fixed, extra, extra2,
            offsets, slots,
        )  # fmt: skip

    def place(self, slots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(per universe action its index, per fluent atom its flat observation position; -1
        for none) with local object i in slot ``slots[i]``."""
        at = np.append(np.asarray(slots), -1)  # at[-1] = -1: "not in the scene" stays -1
        slot, m, g = at[self.obj], self.member, self.grasp
        support = np.where(self.support_obj >= 0, at[self.support_obj], self.support_fixed)
        k = self.k
        place0 = k * _M * _G
        slide0 = place0 + k * (k + _R)
        pick = (slot * _M + m) * _G + g
        place = place0 + slot * (k + _R) + support
        slide = slide0 + ((slot * _M + m) * _G + g) * _S + self.space
        member_ok = (m >= 0) & (m < _M)
        valid = (
            (slot >= 0)
            & (g >= 0)
            & np.choose(self.op, [member_ok, support >= 0, member_ok & (self.space >= 0)])
        )
        index = np.where(valid, np.choose(self.op, [pick, place, slide]), -1)
        off, e, n_p = self.offsets, n_entities(k), len(PARTS)
        ea = np.where(self.a_obj >= 0, at[self.a_obj], self.a_fixed)
        eb = np.where(self.b_obj >= 0, at[self.b_obj], self.b_fixed)
        x, kind = self.extra, self.kind
        pos = np.select(
            [kind == 0, kind == 1, kind == 2, kind == 3, kind == 4, kind == 5],
            [off["held"] + eb, off["in_workspace"] + eb,
             off["member_in_workspace"] + ea * _M + x, off["free"] + ea * n_p + x,
             off["contact"] + (ea * e + eb) * n_p + x,
             off["grasp"] + (ea * _M + x) * _G + self.extra2],
            -1,
        )  # fmt: skip
        ok = np.select(
            [kind == 0, kind == 1, kind == 2, kind == 3, kind == 4, kind == 5],
            [eb >= 0, eb >= 0, ea >= 0, ea >= 0, (ea >= 0) & (eb >= 0), ea >= 0],
            False,
        )
        return index, np.where(ok, pos, -1)


@lru_cache(maxsize=16)
def shared_maps(key: UniverseKey, k: int = _K) -> SceneCache[SceneMap]:
    """The scene maps of one universe under declared types, shared by every interface of a
    process (the 8 envs of a training vector derive each scene once, not once each); a map is
    never modified after it is made."""
    return SceneCache()
