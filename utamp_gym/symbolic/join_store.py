"""A domain's join orders, kept on disk (`symbolic.store`) so a new process does not work
them out again.

`join_plan` orders some thirty joins per domain (one per static group of a schema and one
per seed literal of its main join); in a fresh process that was most of a grounder's
start-up. The orders are a pure function of the joins and of `symbolic.joins`, so they are
stored under a key naming both: per join order, per step the index of its literal and its
checks in the join, its positions and variable names.
"""

from __future__ import annotations

from collections.abc import Sequence
from operator import itemgetter
from typing import Any

from utamp_gym.symbolic import store
from utamp_gym.symbolic.joins import Join, JoinPlan, Step, join_plan

KIND = "joins"


def _encode(join: Join, plan: JoinPlan) -> tuple[Any, ...]:
    steps, late, unbound = plan
    index = {c: k for k, c in enumerate(join.checks)}
    out = []
    for s in steps:
        names = () if s.getter is None else tuple(s.atom.args[p] for p in s.positions)
        at = join.positive.index(s.atom)
        ready = tuple(index[c] for c in s.checks)
        out.append((at, s.use_delta, ready, s.consts, s.positions, names, s.free, s.repeats))
    return tuple(out), tuple(index[c] for c in late), unbound


def _decode(join: Join, data: tuple[Any, ...]) -> JoinPlan:
    steps, late, unbound = data
    positive, checks = join.positive, join.checks
    out = []
    for at, delta, ready, consts, positions, names, free, repeats in steps:
        if not (type(consts) is type(positions) is type(free) is type(repeats) is tuple):
            raise TypeError("not a stored join order")
        getter = itemgetter(*names) if names else None
        pre = tuple(checks[k] for k in ready) if ready else ()
        out.append(Step(positive[at], delta is True, pre, consts, positions, getter, free, repeats))
    if type(unbound) is not tuple:
        raise TypeError("not a stored join order")
    return tuple(out), tuple(checks[k] for k in late), unbound


def _key(wanted: Sequence[tuple[Join, int | None]]) -> str:
    # each join once (a main join comes with each of its seeds), as plain tuples: their
    # repr is written in C, a named tuple's in Python
    index: dict[int, int] = {}
    plain, seeds = [], []
    for j, seed in wanted:
        if id(j) not in index:
            index[id(j)] = len(plain)
            checks = tuple((tuple(c.atom), c.positive) for c in j.checks)
            plain.append((tuple(map(tuple, j.positive)), checks, j.variables))
        seeds.append((index[id(j)], seed))
    return store.key_of(store.sources(join_plan.__module__), repr(plain), repr(seeds))


_known: dict[tuple[tuple[Join, int | None], ...], list[JoinPlan]] = {}  # this process's


def join_plans(wanted: Sequence[tuple[Join, int | None]]) -> list[JoinPlan]:
    """`join_plan` of each (join, seed) in `wanted`: the ones this process has, else stored
    ones when the store has them, else worked out (and stored)."""
    wanted = tuple(wanted)
    plans = _known.get(wanted)
    if plans is None:
        plans = _known[wanted] = _load_or_make(wanted)
    return plans


def _load_or_make(wanted: tuple[tuple[Join, int | None], ...]) -> list[JoinPlan]:
    try:
        key = _key(wanted)
    except OSError:  # the module's source cannot be read: no store
        return [join_plan(j, s) for j, s in wanted]
    stored = store.load(KIND, key)
    if stored is not None:
        try:
            if len(stored) == len(wanted):
                return [_decode(j, p) for (j, _), p in zip(wanted, stored, strict=True)]
        except store.UNREADABLE:
            pass
    plans = [join_plan(j, s) for j, s in wanted]
    encoded = tuple(_encode(j, p) for (j, _), p in zip(wanted, plans, strict=True))
    store.save(KIND, key, encoded)
    return plans


__all__ = ["KIND", "join_plans"]
