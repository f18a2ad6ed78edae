"""Full grounding of a parsed PDDL task into a compact, bit-packed STRIPS task.

Why: the Gymnasium env steps the symbolic task tens of thousands of times per second and
needs the applicable-action mask at every step. `GroundTask` keeps one uint64 bit row per
ground action (preconditions, negative preconditions, add and delete effects), so the mask
over all actions is a few vectorised numpy operations on the packed state.

Static predicates (those in no effect) are evaluated here and dropped. Action parameters are
bound by a backtracking join whose variable order follows the static preconditions, using
per-(predicate, position) indices of the static facts, so selective static predicates keep
even ~11-parameter schemas cheap. Atoms and actions are sorted by their PDDL text, so ids are
stable for a given domain, object set and static facts.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from utamp_gym.errors import UnknownNameError
from utamp_gym.symbolic.pddl import Action, Domain, Literal, Problem, check_problem

_EMPTY: frozenset[str] = frozenset()


class _GroundAction(NamedTuple):
    label: str
    pre: tuple[str, ...]
    neg: tuple[str, ...]
    add: tuple[str, ...]
    dele: tuple[str, ...]


def _text(pred: str, args: Sequence[str]) -> str:
    return "(" + " ".join((pred, *args)) + ")"


def _csr(rows: list[tuple[str, ...]], ids: Mapping[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """Row pointers and flat atom ids of per-action atom lists."""
    ptr = np.zeros(len(rows) + 1, np.int64)
    ptr[1:] = np.cumsum([len(r) for r in rows])
    flat = np.fromiter((ids[a] for r in rows for a in r), np.int64, int(ptr[-1]))
    return ptr, flat


def _bits(ptr: np.ndarray, flat: np.ndarray, n_words: int) -> np.ndarray:
    """(rows, n_words) uint64 matrix with bit `id % 64` of word `id // 64` set per atom id."""
    out = np.zeros((len(ptr) - 1, n_words), np.uint64)
    rows = np.repeat(np.arange(len(ptr) - 1), np.diff(ptr))
    np.bitwise_or.at(out, (rows, flat >> 6), np.left_shift(np.uint64(1), (flat & 63).astype(
        np.uint64)))
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False, repr=False)
class GroundTask:
    """A grounded STRIPS task; states are bool vectors over `atoms` (or packed uint64 words).

    `pre`, `neg`, `add`, `dele` are (n_actions, n_words) uint64 bit matrices; bit ``j % 64``
    of word ``j // 64`` stands for atom ``j``. `goal_pos`/`goal_neg` are packed goal masks;
    `goal_possible` is False when a static goal literal is false. Arrays are read-only.
    """

    atoms: tuple[str, ...]
    actions: tuple[str, ...]
    init: np.ndarray
    pre: np.ndarray
    neg: np.ndarray
    add: np.ndarray
    dele: np.ndarray
    goal_pos: np.ndarray
    goal_neg: np.ndarray
    goal_possible: bool
    labels: tuple[str, ...]  # atoms with predicates spelled as in the domain
    csr: Mapping[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    _index: Mapping[str, int] = field(default_factory=dict)

    def __repr__(self) -> str:
        return f"GroundTask(n_atoms={len(self.atoms)}, n_actions={len(self.actions)})"

    @property
    def n_words(self) -> int:
        return self.pre.shape[1]

    def _ids(self, kind: str, i: int) -> np.ndarray:
        ptr, flat = self.csr[kind]
        return flat[ptr[i]:ptr[i + 1]]

    def pack(self, state: np.ndarray) -> np.ndarray:
        """Bool state vector -> packed uint64 words."""
        buf = np.zeros(self.n_words * 8, np.uint8)
        packed = np.packbits(state, bitorder="little")
        buf[: packed.size] = packed
        return buf.view("<u8").astype(np.uint64, copy=False)

    def unpack(self, words: np.ndarray) -> np.ndarray:
        """Packed uint64 words -> bool state vector."""
        raw = np.asarray(words, "<u8").view(np.uint8)
        return np.unpackbits(raw, count=len(self.atoms), bitorder="little").astype(bool)

    def applicable_packed(self, words: np.ndarray) -> np.ndarray:
        """Bool mask over all actions for a packed state."""
        viol = (self.pre & ~words) | (self.neg & words)
        return ~viol.any(axis=1)

    def applicable(self, state: np.ndarray) -> np.ndarray:
        """Bool mask over all actions: every precondition true, every negated one false."""
        return self.applicable_packed(self.pack(state))

    def is_applicable(self, state: np.ndarray, i: int) -> bool:
        """Whether action `i` is applicable in bool `state`."""
        return bool(state[self._ids("pre", i)].all() and not state[self._ids("neg", i)].any())

    def apply(self, state: np.ndarray, i: int) -> np.ndarray:
        """Successor of bool `state` under action `i` (delete, then add; input untouched).

        Does not check applicability; use `applicable`/`is_applicable` first.
        """
        out = np.array(state, dtype=bool)
        out[self._ids("dele", i)] = False
        out[self._ids("add", i)] = True
        return out

    def apply_packed(self, words: np.ndarray, i: int) -> np.ndarray:
        """Successor of a packed state under action `i` (no applicability check)."""
        return (words & ~self.dele[i]) | self.add[i]

    def is_goal(self, state: np.ndarray) -> bool:
        """Whether bool `state` satisfies every goal literal."""
        return self.is_goal_packed(self.pack(state))

    def is_goal_packed(self, words: np.ndarray) -> bool:
        return self.goal_possible and not (
            (self.goal_pos & ~words).any() or (self.goal_neg & words).any())

    def index_of(self, action: str | Sequence[str]) -> int:
        """Id of a ground action given as ``"(pick a s1)"`` or ``("pick", "a", "s1")``."""
        parts = action.strip().strip("()").split() if isinstance(action, str) else action
        key = "(" + " ".join(str(p).lower() for p in parts) + ")"
        try:
            return self._index[key]
        except KeyError:
            raise UnknownNameError("ground action", key, self.actions) from None

    def failed_preconditions(self, state: np.ndarray, i: int) -> list[str]:
        """Precondition literals of action `i` that are false in bool `state`, as PDDL."""
        bad = [self.labels[j] for j in self._ids("pre", i) if not state[j]]
        return bad + [f"(not {self.labels[j]})" for j in self._ids("neg", i) if state[j]]

    def true_atoms(self, state: np.ndarray) -> list[str]:
        """The fluent atoms true in bool `state`, in id order."""
        return [self.atoms[j] for j in np.flatnonzero(state)]


def ground(domain: Domain, problem: Problem, *, relevant_only: bool = False) -> GroundTask:
    """Ground `problem` over `domain` into a `GroundTask`.

    By default every ground action whose static preconditions (including types, ``=`` and
    ``not =``) hold is kept, so the action set depends only on the objects and static facts,
    not on the fluent initial state. With ``relevant_only=True`` only actions reachable from
    the initial state under delete relaxation (negative preconditions ignored) are kept:
    smaller, but the action set, and hence action ids, then change with the initial state.
    """
    check_problem(domain, problem)
    objects = {**domain.constants, **problem.objects}
    by_type = {t: sorted(o for o, ot in objects.items() if domain.is_subtype(ot, t))
               for t in domain.types}
    fluent = domain.fluent_predicates()
    static: dict[str, set[tuple[str, ...]]] = {p: set() for p in domain.predicates
                                               if p not in fluent}
    index: dict[tuple[str, int, tuple[str, ...]], set[str]] = {}
    for atom in problem.init:
        if atom.predicate in static:
            static[atom.predicate].add(atom.args)
            for k, arg in enumerate(atom.args):
                rest = atom.args[:k] + atom.args[k + 1:]
                index.setdefault((atom.predicate, k, rest), set()).add(arg)
    grounded = [g for name in sorted(domain.actions)
                for g in _ground_action(domain.actions[name], by_type, static, index)]
    init = {str(a) for a in problem.init if a.predicate in fluent}
    if relevant_only:
        grounded = _relaxed_reachable(grounded, init)
    grounded.sort(key=lambda g: g.label)
    goal = [lit for lit in problem.goal if lit.atom.predicate in fluent]
    possible = all((lit.atom.args in static[lit.atom.predicate]) == lit.positive
                   for lit in problem.goal if lit.atom.predicate not in fluent)
    atoms = sorted(init.union({str(lit.atom) for lit in goal},
                              *(g.pre + g.neg + g.add + g.dele for g in grounded)))
    ids = {a: j for j, a in enumerate(atoms)}
    n_words = max(1, -(-len(atoms) // 64))
    csr = {kind: _csr([getattr(g, kind) for g in grounded], ids)
           for kind in ("pre", "neg", "add", "dele")}
    goal_csr = {sign: _csr([tuple(str(lit.atom) for lit in goal if lit.positive == sign)], ids)
                for sign in (True, False)}
    init_vec = np.zeros(len(atoms), bool)
    init_vec[[ids[a] for a in init]] = True
    init_vec.setflags(write=False)
    labels = tuple("(" + " ".join((domain.spelling.get(a[1:-1].split()[0], a[1:-1].split()[0]),
                                   *a[1:-1].split()[1:])) + ")" for a in atoms)
    return GroundTask(
        atoms=tuple(atoms), actions=tuple(g.label for g in grounded), init=init_vec,
        pre=_bits(*csr["pre"], n_words), neg=_bits(*csr["neg"], n_words),
        add=_bits(*csr["add"], n_words), dele=_bits(*csr["dele"], n_words),
        goal_pos=_bits(*goal_csr[True], n_words)[0], goal_neg=_bits(*goal_csr[False], n_words)[0],
        goal_possible=possible, labels=labels, csr=csr,
        _index={g.label: i for i, g in enumerate(grounded)})


def _ground_action(action: Action, by_type: Mapping[str, list[str]],
                   static: Mapping[str, set[tuple[str, ...]]],
                   index: Mapping[tuple[str, int, tuple[str, ...]], set[str]],
                   ) -> Iterator[_GroundAction]:
    """All ground instances of `action` whose static preconditions hold."""
    types = dict(action.parameters)
    lits = [lit for lit in action.precondition
            if lit.atom.predicate == "=" or lit.atom.predicate in static]
    fluent = [lit for lit in action.precondition if lit not in lits]

    def variables(lit: Literal) -> set[str]:
        return {a for a in lit.atom.args if a.startswith("?")}

    # Variable order: prefer a variable pinned by `=` or looked up in a static index given the
    # variables bound so far; then one in many positive static literals; then a small type.
    order: list[str] = []
    pending = [lit for lit in lits if variables(lit)]
    if not all(_static_holds(lit, {}, static) for lit in lits if not variables(lit)):
        return
    while len(order) < len(types):
        bound = set(order)

        def score(v: str, bound: set[str] = bound) -> tuple[int, int, int]:
            pos = [lit for lit in pending if lit.positive and v in variables(lit)]
            pinned = max((2 if lit.atom.predicate == "=" else 1 for lit in pos
                          if variables(lit) - {v} <= bound), default=0)
            return -pinned, -len(pos), len(by_type[types[v]])

        order.append(min((v for v in types if v not in bound), key=score))
    # At each depth, the literals whose last unbound variable is bound there.
    checks = [[lit for lit in pending if v in variables(lit)
               and variables(lit) <= set(order[: d + 1])] for d, v in enumerate(order)]
    type_sets = {t: set(objs) for t, objs in by_type.items()}
    binding: dict[str, str] = {}

    def candidates(v: str, depth: int) -> list[str]:
        pins: list[set[str] | frozenset[str]] = []
        excluded: set[str] = set()
        slow: list[Literal] = []
        for lit in checks[depth]:
            pred, args = lit.atom.predicate, lit.atom.args
            where = [k for k, a in enumerate(args) if a == v]
            if pred == "=":
                others = [binding.get(a, a) for a in args if a != v]
                if not others:
                    if not lit.positive:
                        return []
                    continue
                hit: set[str] | frozenset[str] = {others[0]}
            elif len(where) == 1:
                k = where[0]
                rest = tuple(binding.get(a, a) for a in args[:k] + args[k + 1:])
                hit = index.get((pred, k, rest), _EMPTY)
            else:
                slow.append(lit)
                continue
            if lit.positive:
                pins.append(hit)
            else:
                excluded |= hit
        typed = type_sets[types[v]]
        if pins:
            pins.sort(key=len)
            out = [c for c in pins[0] if c in typed and c not in excluded
                   and all(c in s for s in pins[1:])]
        else:
            out = [c for c in by_type[types[v]] if c not in excluded]
        for lit in slow:
            out = [c for c in out if _static_holds(lit, {**binding, v: c}, static)]
        return out

    def ground_atoms(sign: bool | None, atoms: Sequence[Literal]) -> tuple[str, ...]:
        return tuple(_text(lit.atom.predicate, [binding.get(a, a) for a in lit.atom.args])
                     for lit in atoms if sign is None or lit.positive == sign)

    add = [Literal(a) for a in action.add_effects]
    dele = [Literal(a) for a in action.del_effects]
    params = [v for v, _ in action.parameters]

    def search(depth: int) -> Iterator[_GroundAction]:
        if depth == len(order):
            yield _GroundAction(
                _text(action.name, [binding[v] for v in params]),
                ground_atoms(True, fluent), ground_atoms(False, fluent),
                ground_atoms(None, add), ground_atoms(None, dele))
            return
        v = order[depth]
        for c in candidates(v, depth):
            binding[v] = c
            yield from search(depth + 1)
        binding.pop(v, None)

    yield from search(0)


def _static_holds(lit: Literal, binding: Mapping[str, str],
                  static: Mapping[str, set[tuple[str, ...]]]) -> bool:
    args = tuple(binding.get(a, a) for a in lit.atom.args)
    true = args[0] == args[1] if lit.atom.predicate == "=" else args in static[lit.atom.predicate]
    return true == lit.positive


def _relaxed_reachable(actions: list[_GroundAction], init: set[str]) -> list[_GroundAction]:
    """Actions reachable from `init` ignoring delete effects and negative preconditions."""
    waiting: dict[str, list[int]] = {}
    missing = []
    for i, g in enumerate(actions):
        need = set(g.pre)
        missing.append(len(need))
        for a in need:
            waiting.setdefault(a, []).append(i)
    reached = set(init)
    queue = list(init)
    ready = [i for i, m in enumerate(missing) if m == 0]
    keep = set()
    while ready or queue:
        while ready:
            i = ready.pop()
            keep.add(i)
            for a in actions[i].add:
                if a not in reached:
                    reached.add(a)
                    queue.append(a)
        if queue:
            for i in waiting.get(queue.pop(), ()):
                missing[i] -= 1
                if missing[i] == 0:
                    ready.append(i)
    return [g for i, g in enumerate(actions) if i in keep]
