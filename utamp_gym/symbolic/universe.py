"""The action universe of an env configuration: one fixed, ordered set of ground macro actions.

Why: a `Discrete` action id must name the same ground action in every episode, whatever scene
is sampled. So the actions are grounded once per configuration over a *universe* problem whose
objects and initial atoms are the union over all the configuration's scenes. Relaxed
reachability (`symbolic.reach`) is monotone in the initial atoms, so the universe's reachable
ops contain every scene's reachable ops. Static negative preconditions only prune during
grounding for predicates whose atoms hold in every scene that has their objects; afterwards
an op is kept if its static precondition holds in at least one scene (for noisy affordances:
ignoring negated affordance facts, which a detection may drop). Actions are sorted by their
PDDL string.

Each op keeps its full precondition: static atoms (affordances, geometry: decided once per
episode, so absent objects and missing affordances mask ops out) as rows of a uint64 bit matrix
over `static_atoms`, and fluent atoms (decided per step) as one flat index array
(`check_flat`, rows delimited by `check_ptr`) into the *extended* state bits ``[s, 1 - s]``:
a positive literal on atom j indexes ``half + j``, a negative one ``j``, so an op's number of
violated fluent literals is a gather and an `np.add.reduceat` over all ops at once. A fluent
state is a Python int (bit j = atom j of `fluent_atoms`); effects are `add_bits`/`del_bits`.

Precondition sets (`UniverseKey.preconditions`): ``"affordances"`` grounds the key's domain
as written; ``"geometric"`` grounds `geometric.geometric_domain` (U-TAMP-2 without affordance
literals) and prunes ops no real state allows (`geometric.prune`). The affordance universes
are left exactly as they were: their action ids are fixed.

Caching: `ground_universe` is a `functools.lru_cache` (bounded) on a pure function of the
frozen, hashable `UniverseKey`; the result is immutable (read-only arrays, tuples, ints), so
envs share it safely and pickle it by key. No registry or env holds a mutable cache of it;
each process (e.g. an async vector env worker) grounds once per key, in 0.2-30 s, unless an
earlier process stored it on disk (`utamp_gym.symbolic.universe_store`: named by the key and the
package's contents), which a new process reads instead.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType
from typing import Any

import numpy as np

from utamp_gym.affordances.facts import PREDICATES as AFFORDANCE_PREDICATES
from utamp_gym.errors import PddlError, UnknownNameError
from utamp_gym.scene.geometry import PARTS
from utamp_gym.scene.model import BuiltScene, Scene
from utamp_gym.suites import resolve_scene, universe_scenes
from utamp_gym.symbolic import universe_store
from utamp_gym.symbolic.atoms import goal_sides, parse_atom, scene_atoms, universe_facts
from utamp_gym.symbolic.geometric import geometric_domain, prune
from utamp_gym.symbolic.pddl import Domain, Literal, Problem, parse_domain
from utamp_gym.symbolic.problem import domain_text, problem_goal
from utamp_gym.symbolic.reach import reachable_ops

#: the macro actions whose pose effects the envs model: name -> (moved object, target) params
ROLES: Mapping[str, tuple[str, str]] = MappingProxyType(
    {
        "pick-support": ("?obj1", "?obj2"),
        "place-support": ("?obj1", "?obj2"),
        "slide-support": ("?obj1", "?space"),
        "slide-edge": ("?obj1", "?obj2"),
        "place-edge": ("?obj1", "?obj2"),
    }
)
#: the extended domain's actions (``utamp2x``) move objects as these paper actions do: a
#: board slid to the table's edge ends up in the hand, then on a slot
MOVES_LIKE: Mapping[str, str] = MappingProxyType(
    {"slide-edge": "pick-support", "place-edge": "place-support"}
)
_AFFORDANCE_PREDS = frozenset(p.lower() for p in AFFORDANCE_PREDICATES)
#: which preconditions a universe's actions are grounded (and masked) with
PRECONDITIONS = ("affordances", "geometric")


@dataclass(frozen=True)
class UniverseKey:
    """What the universe depends on: domain, affordance source, the scenes' references and
    the precondition set.

    `affordances` is ``"none"`` for U-TAMP-1 (no affordance predicates) and for geometric
    preconditions (they mention none); `scenes` are names that `resolve_scene` understands,
    or scenes built in code (`BuiltScene`, by content: such a scene never shares a key with
    a packaged one of its name) (suite scenes are given by `suite`: a suite, or
    ``procedural-v1`` for all its splits);
    `preconditions` is one of `PRECONDITIONS` (see the
    module docstring; ``"geometric"`` needs the utamp2 domain).
    """

    domain: str
    affordances: str
    suite: str | None = None
    scenes: tuple[str | BuiltScene, ...] = ()
    preconditions: str = "affordances"

    def __post_init__(self) -> None:
        if self.preconditions not in PRECONDITIONS:
            raise UnknownNameError("precondition set", self.preconditions, PRECONDITIONS)
        if self.preconditions == "geometric" and (self.domain, self.affordances) != (
            "utamp2",
            "none",
        ):
            raise ValueError(
                "geometric preconditions are U-TAMP-2's without affordances: they need "
                f"domain 'utamp2' and affordances 'none', got {self.domain!r}, "
                f"{self.affordances!r}"
            )

    def resolve(self) -> tuple[Scene, ...]:
        base = universe_scenes(self.suite) if self.suite is not None else ()
        known = {s.name for s in base}
        return (
            *base,
            *(r.scene if isinstance(r, BuiltScene) else resolve_scene(r)
              for r in self.scenes if r not in known),
        )  # fmt: skip


def _pack(rows: Sequence[Sequence[int]], n_bits: int) -> np.ndarray:
    """(len(rows), n_words) uint64 matrix with the listed bit ids set; read-only."""
    n_words = max(1, -(-n_bits // 64))
    out = np.zeros((len(rows), n_words), np.uint64)
    lengths = [len(r) for r in rows]
    flat = np.fromiter((j for r in rows for j in r), np.int64, sum(lengths))
    where = np.repeat(np.arange(len(rows)), lengths)
    bits = np.left_shift(np.uint64(1), (flat & 63).astype(np.uint64))
    np.bitwise_or.at(out, (where, flat >> 6), bits)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class Universe:
    """The grounded action universe of one `UniverseKey` (see the module docstring)."""

    key: UniverseKey
    domain: Domain
    actions: tuple[str, ...]  # "(pick-support mug mug-handle ...)", sorted
    fluent_atoms: tuple[str, ...]  # lower-case PDDL, sorted: the "symbolic" observation order
    static_atoms: tuple[str, ...]
    add_bits: tuple[int, ...]
    del_bits: tuple[int, ...]
    check_ptr: np.ndarray  # (n_actions + 1,) row starts into check_flat
    check_flat: np.ndarray  # extended-bit indices of every fluent literal (module docstring)
    static_pre: np.ndarray  # static positive preconditions, (n_actions, static words)
    static_neg: np.ndarray  # static negative preconditions that some scene can violate
    roles: tuple[tuple[str, str, str], ...]  # (paper action it moves like, moved, target)
    action_objects: tuple[tuple[str, ...], ...]  # scene symbols among each action's arguments
    action_index: Mapping[str, int]
    fluent_index: Mapping[str, int]
    static_index: Mapping[str, int]

    def __repr__(self) -> str:
        return (
            f"Universe({self.key}, n_actions={len(self.actions)}, "
            f"n_fluents={len(self.fluent_atoms)}, n_static={len(self.static_atoms)})"
        )

    @property
    def n_actions(self) -> int:
        return len(self.actions)

    def index(self, action: str) -> int:
        """Id of a ground action given as PDDL text; `UnknownNameError` lists the valid ones."""
        key = "(" + " ".join(action.strip().strip("()").lower().split()) + ")"
        try:
            return self.action_index[key]
        except KeyError:
            raise UnknownNameError("ground action", action, self.actions) from None

    @property
    def half(self) -> int:
        """Bits per half of the extended state ``[s, 1 - s]`` (> n fluents, byte-aligned)."""
        return 8 * ((len(self.fluent_atoms) + 8) // 8)

    def state_bits(self, atoms: Iterable[str]) -> int:
        """Fluent state (Python int) of lower-case atoms (all must be in the universe)."""
        bits = 0
        for a in atoms:
            bits |= 1 << self.fluent_index[a]
        return bits

    def atoms_of(self, bits: int) -> list[str]:
        """The atoms set in a fluent state, in `fluent_atoms` order."""
        return [a for j, a in enumerate(self.fluent_atoms) if bits >> j & 1]

    def successor(self, bits: int, i: int) -> int:
        """State after action `i` (delete, then add); applicability is not checked."""
        return (bits & ~self.del_bits[i]) | self.add_bits[i]

    def pack_static(self, atoms: Iterable[str]) -> np.ndarray:
        """Packed static state; atoms no op mentions are dropped (they decide nothing)."""
        ids = [self.static_index[a] for a in atoms if a in self.static_index]
        return _pack([ids], len(self.static_atoms))[0].copy()

    def static_ok(self, static_words: np.ndarray) -> np.ndarray:
        """Bool mask: the ops whose static preconditions hold in a packed static state."""
        viol = (self.static_pre & ~static_words) | (self.static_neg & static_words)
        return ~viol.any(axis=1)

    def preconditions(self, i: int) -> tuple[Literal, ...]:
        """Full precondition of action `i`, in the domain's order (cached: failing steps of
        agents without masks ask for it at every step)."""
        return _preconditions(self, i)


@lru_cache(maxsize=16_384)
def _preconditions(universe: Universe, i: int) -> tuple[Literal, ...]:
    name, *args = universe.actions[i].strip("()").split()
    return universe.domain.actions[name].instantiate(args)[0]


def universe_domain(key: UniverseKey) -> Domain:
    """The domain whose preconditions a universe's actions are grounded with."""
    if key.preconditions == "geometric":
        return geometric_domain()
    return parse_domain(domain_text(key.domain), source=f"{key.domain}.pddl")


def _relaxed_domain(domain: Domain, keep: frozenset[str]) -> Domain:
    """The domain without the static negative preconditions whose predicate is not in `keep`."""
    fluent = domain.fluent_predicates()
    actions = {
        name: act._replace(
            precondition=tuple(
                lit
                for lit in act.precondition
                if lit.positive or lit.atom.predicate in fluent | keep | {"="}
            ),
        )
        for name, act in domain.actions.items()
    }
    return domain._replace(actions=MappingProxyType(actions))


def _uniform_predicates(
    scenes: Sequence[tuple[frozenset[str], frozenset[str]]],
    union: set[str],
    varying: frozenset[str],
    constants: frozenset[str],
) -> frozenset[str]:
    """Static predicates whose atoms hold in every scene that has all of the atom's objects.

    For these, a static negative precondition true in the union is true wherever the op's
    objects exist, so the grounder may prune with it exactly. `scenes`: (static atoms, objects).
    """
    preds: dict[str, bool] = {}
    for text in union:
        atom = parse_atom(text)
        if atom.predicate in varying:
            preds[atom.predicate] = False
            continue
        need = set(atom.args)
        uniform = all(text in static for static, objs in scenes if need <= objs | constants)
        preds[atom.predicate] = preds.get(atom.predicate, True) and uniform
    return frozenset(p for p, ok in preds.items() if ok)


@lru_cache(maxsize=16)
def ground_universe(key: UniverseKey) -> Universe:
    """The universe of `key`: grounded once per process (cached: see the module docstring),
    and read from `universe_store` when an earlier process of this package stored it."""
    stored = universe_store.load(key)
    if stored is not None:
        return _from_store(key, *stored)
    universe = _ground(key)
    universe_store.save(key, *_to_store(universe))
    return universe


_ARRAYS = ("check_ptr", "check_flat", "static_pre", "static_neg")


def _to_store(u: Universe) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    fields = {
        "actions": list(u.actions), "fluent_atoms": list(u.fluent_atoms),
        "static_atoms": list(u.static_atoms), "add_bits": [f"{b:x}" for b in u.add_bits],
        "del_bits": [f"{b:x}" for b in u.del_bits], "roles": [list(r) for r in u.roles],
        "action_objects": [list(a) for a in u.action_objects],
    }  # fmt: skip
    return fields, {name: getattr(u, name) for name in _ARRAYS}


def _from_store(
    key: UniverseKey, fields: dict[str, Any], arrays: dict[str, np.ndarray]
) -> Universe:
    for a in arrays.values():
        a.setflags(write=False)
    actions, fluent, static = (tuple(fields[k]) for k in ("actions", "fluent_atoms",
                                                          "static_atoms"))  # fmt: skip
    return Universe(
        key=key, domain=universe_domain(key), actions=actions, fluent_atoms=fluent,
        static_atoms=static, add_bits=tuple(int(b, 16) for b in fields["add_bits"]),
        del_bits=tuple(int(b, 16) for b in fields["del_bits"]),
        check_ptr=arrays["check_ptr"], check_flat=arrays["check_flat"],
        static_pre=arrays["static_pre"], static_neg=arrays["static_neg"],
        roles=tuple(tuple(r) for r in fields["roles"]),  # type: ignore[misc]
        action_objects=tuple(tuple(a) for a in fields["action_objects"]),
        action_index=MappingProxyType({a: i for i, a in enumerate(actions)}),
        fluent_index=MappingProxyType({a: j for j, a in enumerate(fluent)}),
        static_index=MappingProxyType({a: j for j, a in enumerate(static)}),
    )  # fmt: skip


def _ground(key: UniverseKey) -> Universe:
    """Ground the universe of `key` (module docstring)."""
    domain = universe_domain(key)
    fluent_preds = domain.fluent_predicates()
    non_static = fluent_preds | {"="}
    # a noisy detection may add or drop any affordance fact in any episode
    varying = _AFFORDANCE_PREDS if key.affordances == "noisy" else frozenset()
    per_scene: list[tuple[frozenset[str], frozenset[str]]] = []
    inits: list[tuple[frozenset[str], frozenset[str]]] = []
    union_static: set[str] = set()
    union_fluent: set[str] = set()
    goals: set[str] = set()
    objects: dict[str, str] = {}
    for scene in key.resolve():
        static, fluent, objs = scene_atoms(
            scene, universe_facts(scene, key.affordances, key.domain), key.domain, fluent_preds
        )
        per_scene.append((static, frozenset(objs)))
        inits.append((fluent, frozenset(objs) | set(domain.constants) | set(PARTS)))
        union_static |= static
        union_fluent |= fluent
        goals |= set().union(*goal_sides(problem_goal(scene)))  # its goal, else the tower
        objects.update(dict.fromkeys(objs, "obj"))
    uniform = _uniform_predicates(
        per_scene, union_static, varying, frozenset(domain.constants) | set(PARTS)
    )
    problem = Problem(
        "universe",
        domain.name,
        MappingProxyType(objects),
        frozenset(parse_atom(a) for a in union_static | union_fluent),
        (),
    )
    # conditional effects are resolved once, so their conditions must agree between scenes
    conditions = domain.condition_predicates()
    cond_facts = frozenset(a for a in problem.init if a.predicate in conditions)
    differ = {a.predicate for a in cond_facts} - uniform
    if differ:
        raise PddlError(
            f"{key.domain}.pddl: conditional effects depend on static predicates that differ "
            f"between the scenes of {key}: {', '.join(sorted(differ))}"
        )
    ops, reached, _ = reachable_ops(_relaxed_domain(domain, uniform), problem)
    if key.preconditions == "geometric":
        ops = prune(ops, inits, problem.init)
        reached = set(problem.init) | {a for op in ops for a in op.add}
    fluent_atoms = tuple(sorted({str(a) for a in reached if a.predicate in fluent_preds} | goals))
    static_atoms = tuple(sorted(union_static))
    f_index = {a: j for j, a in enumerate(fluent_atoms)}
    s_index = {a: j for j, a in enumerate(static_atoms)}

    rows: dict[str, list[list[int]]] = {k: [] for k in ("pre", "neg", "sp", "sn")}
    add_bits: list[int] = []
    del_bits: list[int] = []
    names, roles, fixed_neg, arg_objects = [], [], [], []
    symbols = set(objects)
    for op in sorted(ops, key=lambda o: f"({o.name})"):
        name, *args = op.name.split()
        act = domain.actions[name]
        pre, add, dele = act.instantiate(args, cond_facts)
        names.append(f"({op.name})")
        params = dict(zip((v for v, _ in act.parameters), args, strict=True))
        moved, target = ROLES.get(name, ("", ""))
        roles.append((MOVES_LIKE.get(name, name), params.get(moved, ""), params.get(target, "")))
        arg_objects.append(tuple(dict.fromkeys(a for a in args if a in symbols)))
        add_bits.append(sum(1 << f_index[str(a)] for a in set(add)))
        del_bits.append(sum(1 << f_index[str(a)] for a in set(dele) if str(a) in f_index))
        fl = [(lit, str(lit.atom)) for lit in pre if lit.atom.predicate in fluent_preds]
        st = [(lit, str(lit.atom)) for lit in pre if lit.atom.predicate not in non_static]
        rows["pre"].append([f_index[a] for lit, a in fl if lit.positive])
        # atoms outside the index are never true: their negation always holds
        rows["neg"].append([f_index[a] for lit, a in fl if not lit.positive and a in f_index])
        rows["sp"].append([s_index[a] for lit, a in st if lit.positive])
        rows["sn"].append([s_index[a] for lit, a in st if not lit.positive and a in s_index])
        fixed_neg.append(
            [
                s_index[a]
                for lit, a in st
                if not lit.positive and a in s_index and lit.atom.predicate not in varying
            ]
        )

    # keep the ops whose static precondition holds in at least one scene
    ns = len(static_atoms)
    sp, sn = _pack(rows["sp"], ns), _pack(fixed_neg, ns)
    viable = np.zeros(len(names), bool)
    for static, _ in per_scene:
        words = _pack([[s_index[a] for a in static]], ns)[0]
        viable |= ~((sp & ~words) | (sn & words)).any(axis=1)
    keep = np.flatnonzero(viable)
    names = [names[i] for i in keep]
    pre_ids = tuple(tuple(rows["pre"][i]) for i in keep)
    neg_ids = tuple(tuple(rows["neg"][i]) for i in keep)
    half = 8 * ((len(fluent_atoms) + 8) // 8)
    checks = [
        [half + j for j in p] + list(n) or [len(fluent_atoms)]  # empty: an always-0 bit
        for p, n in zip(pre_ids, neg_ids, strict=True)
    ]
    ptr = np.zeros(len(keep) + 1, np.int64)
    ptr[1:] = np.cumsum([len(c) for c in checks])
    flat = np.fromiter((j for c in checks for j in c), np.int64, int(ptr[-1]))
    ptr.setflags(write=False)
    flat.setflags(write=False)
    return Universe(
        key=key,
        domain=domain,
        actions=tuple(names),
        fluent_atoms=fluent_atoms,
        static_atoms=static_atoms,
        add_bits=tuple(add_bits[i] for i in keep),
        del_bits=tuple(del_bits[i] for i in keep),
        check_ptr=ptr,
        check_flat=flat,
        static_pre=_pack([rows["sp"][i] for i in keep], ns),
        static_neg=_pack([rows["sn"][i] for i in keep], ns),
        roles=tuple(roles[i] for i in keep),
        action_objects=tuple(arg_objects[i] for i in keep),
        action_index=MappingProxyType({a: i for i, a in enumerate(names)}),
        fluent_index=MappingProxyType(f_index),
        static_index=MappingProxyType(s_index),
    )


class UniverseByKey:
    """Pickles its ``universe`` by the universe's key: re-grounded (or taken from this
    process's cache, or the store) on load."""

    universe: Universe

    def __getstate__(self) -> dict[str, object]:
        state = self.__dict__.copy()
        state["universe"] = self.universe.key
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        state["universe"] = ground_universe(state["universe"])  # type: ignore[arg-type]
        self.__dict__.update(state)
