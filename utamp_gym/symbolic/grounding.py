"""Full grounding of a parsed PDDL task into a compact STRIPS task for fast simulation.

Why: the Gymnasium env steps the symbolic task tens of thousands of times per second and needs
the applicable-action mask at every step. Static predicates (in no effect) are evaluated here
and dropped. Parameters are bound by a backtracking join ordered by the static preconditions,
using per-(predicate, position) indices of the static facts; parameters no static literal
constrains are expanded as one numpy cartesian product and atoms are instantiated vectorised.
Atoms and actions are sorted by their PDDL text, so ids are stable for a given domain, object
set and static facts.

Preconditions and effects are CSR lists of atom ids. Dense bit-packed uint64 matrices are
available (`GroundTask.bit_matrices`) but unused: a mask from them costs O(actions x atoms),
measured 1.3x (80 actions) to 40x (5,500 actions) slower than the sparse `applicable`.
"""

from __future__ import annotations

import bisect
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from utamp_gym.errors import PddlError, UnknownNameError
from utamp_gym.symbolic.pddl import Action, Domain, Literal, Problem, check_problem

_CSR = tuple[np.ndarray, np.ndarray]  # (row pointers, flat column ids)
_KINDS = ("pre", "neg", "add", "dele")  # dele = delete effects minus add effects


def _ro(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def _unique(x: np.ndarray, inverse: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Sorted unique values and (if asked) inverse; np.unique's hash path is far slower."""
    order = np.argsort(x) if inverse else None
    sx = np.sort(x) if order is None else x[order]
    first = np.ones(len(x), bool)
    np.not_equal(sx[1:], sx[:-1], out=first[1:])
    inv = np.empty(len(x) if inverse else 0, np.int64)
    if order is not None:
        inv[order] = np.cumsum(first) - 1
    return sx[first], inv


def _csr(rows: np.ndarray, cols: np.ndarray, n_rows: int, n_cols: int) -> _CSR:
    """CSR of (row, col) pairs; duplicates removed, columns sorted within a row."""
    key = _unique(rows * n_cols + cols, inverse=False)[0]
    ptr = np.zeros(n_rows + 1, np.int64)
    ptr[1:] = np.cumsum(np.bincount(key // n_cols, minlength=n_rows))
    return _ro(ptr), _ro(key % n_cols)


@dataclass(frozen=True, eq=False, repr=False)
class GroundTask:
    """A grounded STRIPS task; a state is a bool vector over `atoms`.

    `csr[kind]` (kind: pre, neg, add, dele) is (ptr, ids): action ``i``'s atoms are
    ``ids[ptr[i]:ptr[i+1]]``; ``dele`` omits atoms the action also adds (add wins).
    `literals` is the same per action as ids into ``[state, ~state, True]``. `goal_pos` and
    `goal_neg` are the atom ids of the positive and negated fluent goal literals;
    `goal_possible` is False when a static goal literal is false. Arrays are read-only.
    """

    atoms: tuple[str, ...]
    actions: tuple[str, ...]
    labels: tuple[str, ...]  # atoms with predicates spelled as in the domain
    init: np.ndarray
    csr: Mapping[str, _CSR]
    literals: _CSR
    goal_pos: np.ndarray
    goal_neg: np.ndarray
    goal_possible: bool

    def __repr__(self) -> str:
        return f"GroundTask(n_atoms={len(self.atoms)}, n_actions={len(self.actions)})"

    def ids(self, kind: str, i: int) -> np.ndarray:
        ptr, flat = self.csr[kind]
        return flat[ptr[i]:ptr[i + 1]]

    def applicable(self, state: np.ndarray) -> np.ndarray:
        """Bool mask over all actions: every precondition true, every negated one false."""
        n = len(self.atoms)
        ext = np.ones(2 * n + 1, bool)
        ext[:n] = state
        np.logical_not(ext[:n], out=ext[n:2 * n])
        starts, flat = self.literals
        return np.logical_and.reduceat(ext[flat], starts) if len(starts) else ext[:0]

    def is_applicable(self, state: np.ndarray, i: int) -> bool:
        return bool(state[self.ids("pre", i)].all() and not state[self.ids("neg", i)].any())

    def apply(self, state: np.ndarray, i: int) -> np.ndarray:
        """Successor of `state` under action `i` (input untouched; applicability not checked)."""
        out = np.array(state, dtype=bool)
        out[self.ids("dele", i)] = False
        out[self.ids("add", i)] = True
        return out

    def is_goal(self, state: np.ndarray) -> bool:
        return self.goal_possible and bool(
            state[self.goal_pos].all() and not state[self.goal_neg].any())

    def index_of(self, action: str | Sequence[str]) -> int:
        """Id of a ground action given as ``"(pick a s1)"`` or ``("pick", "a", "s1")``."""
        parts = action.strip().strip("()").split() if isinstance(action, str) else action
        key = "(" + " ".join(str(p).lower() for p in parts) + ")"
        i = bisect.bisect_left(self.actions, key)
        if i == len(self.actions) or self.actions[i] != key:
            raise UnknownNameError("ground action", key, self.actions)
        return i

    def failed_preconditions(self, state: np.ndarray, i: int) -> list[str]:
        """False precondition literals of action `i` in `state` (atom order), as PDDL text."""
        bad = [self.labels[j] for j in self.ids("pre", i) if not state[j]]
        return bad + [f"(not {self.labels[j]})" for j in self.ids("neg", i) if state[j]]

    def true_atoms(self, state: np.ndarray) -> list[str]:
        return [self.atoms[j] for j in np.flatnonzero(state)]

    def pack(self, state: np.ndarray) -> np.ndarray:
        """State -> uint64 words (bit ``j % 64`` of word ``j // 64`` is atom ``j``)."""
        buf = np.zeros(-(-len(self.atoms) // 64) * 8, np.uint8)
        packed = np.packbits(state, bitorder="little")
        buf[: packed.size] = packed
        return buf.view("<u8").astype(np.uint64)

    def unpack(self, words: np.ndarray) -> np.ndarray:
        raw = np.asarray(words, "<u8").view(np.uint8)
        return np.unpackbits(raw, count=len(self.atoms), bitorder="little").astype(bool)

    def bit_matrices(self) -> dict[str, np.ndarray]:
        """Dense (n_actions, n_words) uint64 matrix per kind, rows as `pack`; built per call."""
        out = {}
        for kind, (ptr, flat) in self.csr.items():
            rows = np.zeros((len(self.actions), len(self.atoms)), bool)
            rows[np.repeat(np.arange(len(self.actions)), np.diff(ptr)), flat] = True
            out[kind] = np.array([self.pack(r) for r in rows], np.uint64).reshape(len(rows), -1)
        return out

    def cursor(self, state: np.ndarray | None = None) -> Cursor:
        return Cursor(self, state)


class Cursor:
    """One rollout: the current state and its applicable mask, for fast repeated stepping.

    Small tasks (at most `INCREMENTAL_ABOVE` precondition entries) recompute the mask with
    `GroundTask.applicable`. Larger ones keep per-action counts of unsatisfied literals and a
    step updates only the actions that mention a changed atom; the up to 64 atoms used by the
    most actions ("hubs", e.g. hand-empty) are instead per-action bit masks checked only for
    actions whose other literals hold, so toggling them does not touch every pick action.
    `state` and `mask` are read-only views overwritten by the next `step`/`reset`.
    """

    INCREMENTAL_ABOVE = 8000  # precondition entries
    HUB_MIN_USERS = 64  # hubs are used by more than max(this, n_actions / 64) actions

    def __init__(self, task: GroundTask, state: np.ndarray | None = None):
        self.task = task
        n_act, n = len(task.actions), len(task.atoms)
        self._state, self._mask = np.zeros(n, bool), np.zeros(n_act, bool)
        self.state, self.mask = self._state.view(), self._mask.view()
        self.state.setflags(write=False)
        self.mask.setflags(write=False)
        (pp, pf), (qp, qf) = task.csr["pre"], task.csr["neg"]
        self.incremental = len(pf) + len(qf) > self.INCREMENTAL_ABOVE
        if self.incremental:
            rows = np.arange(n_act)
            atoms = np.concatenate([pf, qf])
            acts = np.concatenate([np.repeat(rows, np.diff(pp)), np.repeat(rows, np.diff(qp))])
            neg = np.arange(len(atoms)) >= len(pf)
            count = np.bincount(atoms, minlength=n)
            hubs = np.argsort(-count, kind="stable")[:64]
            self._hubs = hubs[count[hubs] > max(self.HUB_MIN_USERS, n_act // 64)]
            self._bit = np.zeros(n, np.uint64)
            self._bit[self._hubs] = np.left_shift(np.uint64(1), np.arange(
                len(self._hubs), dtype=np.uint64))
            hub = self._bit[atoms] != 0
            self._need_t, self._need_f = np.zeros(n_act, np.uint64), np.zeros(n_act, np.uint64)
            for need, sel in ((self._need_t, hub & ~neg), (self._need_f, hub & neg)):
                np.bitwise_or.at(need, acts[sel], self._bit[atoms[sel]])
            o = np.lexsort((acts[~hub], atoms[~hub]))
            self._atoms, self._users = atoms[~hub][o], acts[~hub][o]
            self._delta = np.where(neg[~hub], 1, -1)[o]  # count change when the atom turns true
            self._ptr = np.zeros(n + 1, np.int64)
            self._ptr[1:] = np.cumsum(np.bincount(self._atoms, minlength=n))
        self.reset(state)

    def reset(self, state: np.ndarray | None = None) -> None:
        self._state[:] = self.task.init if state is None else state
        if not self.incremental:
            self._mask[:] = self.task.applicable(self._state)
            return
        violated = self._state[self._atoms] == (self._delta > 0)
        self._unsat = np.bincount(self._users[violated], minlength=len(self._mask))
        self._ready = self._unsat == 0
        self._gate()

    def _gate(self) -> None:
        """mask = ready and hub literals hold; only the (few) ready actions are examined."""
        word = np.bitwise_or.reduce(self._bit[self._hubs][self._state[self._hubs]])
        ready = np.flatnonzero(self._ready)
        self._mask[:] = False
        self._mask[ready] = ((self._need_t[ready] & ~word) | (self._need_f[ready] & word)) == 0

    def step(self, i: int) -> None:
        """Apply action `i`; `PddlError` naming the false preconditions if not applicable."""
        t, s = self.task, self._state
        if not self._mask[i]:
            raise PddlError(f"action {t.actions[i]} is not applicable: "
                            f"{', '.join(t.failed_preconditions(s, i))} false")
        d, a = t.ids("dele", i), t.ids("add", i)
        if not self.incremental:
            s[d] = False
            s[a] = True
            self._mask[:] = t.applicable(s)
            return
        off, on = d[s[d]], a[~s[a]]
        s[off] = False
        s[on] = True
        changed = np.concatenate((on, off))
        lo = self._ptr[changed]
        n = self._ptr[changed + 1] - lo
        pos = np.repeat(lo - np.cumsum(n) + n, n) + np.arange(int(n.sum()))
        u = self._users[pos]
        sign = np.repeat(np.repeat([1, -1], (on.size, off.size)), n)
        np.add.at(self._unsat, u, self._delta[pos] * sign)
        self._ready[u] = self._unsat[u] == 0
        self._gate()

    def is_goal(self) -> bool:
        return self.task.is_goal(self._state)


class _Statics:
    """Objects by type, and static facts indexed by (predicate, position, other arguments)."""

    def __init__(self, domain: Domain, problem: Problem, fluent: frozenset[str]):
        objects = {**domain.constants, **problem.objects}
        self.names = sorted(objects)
        self.oid = {o: k for k, o in enumerate(self.names)}
        self.by_type = {t: [o for o in self.names if domain.is_subtype(objects[o], t)]
                        for t in domain.types}
        self.type_sets = {t: set(v) for t, v in self.by_type.items()}
        self.facts: dict[str, set[tuple[str, ...]]] = {
            p: set() for p in domain.predicates if p not in fluent}
        self.index: dict[tuple[str, int, tuple[str, ...]], set[str]] = {}
        for atom in problem.init:
            if atom.predicate in self.facts:
                self.facts[atom.predicate].add(atom.args)
                for k, arg in enumerate(atom.args):
                    rest = atom.args[:k] + atom.args[k + 1:]
                    self.index.setdefault((atom.predicate, k, rest), set()).add(arg)

    def holds(self, lit: Literal, binding: Mapping[str, str]) -> bool:
        args = tuple(binding.get(a, a) for a in lit.atom.args)
        true = args[0] == args[1] if lit.atom.predicate == "=" else (
            args in self.facts[lit.atom.predicate])
        return true == lit.positive

    def candidates(self, v: str, typ: str, lits: list[Literal], binding: dict[str, str]
                   ) -> list[str]:
        """Objects for `v` satisfying `lits`, whose other variables are all in `binding`."""
        pins: list[set[str]] = []
        excluded: set[str] = set()
        slow = []
        for lit in lits:
            pred, args = lit.atom.predicate, lit.atom.args
            where = [k for k, a in enumerate(args) if a == v]
            if len(where) != 1:
                slow.append(lit)
                continue
            k = where[0]
            if pred == "=":
                hit = {binding.get(args[1 - k], args[1 - k])}
            else:
                rest = tuple(binding.get(a, a) for a in args[:k] + args[k + 1:])
                hit = self.index.get((pred, k, rest), set())
            if lit.positive:
                pins.append(hit)
            else:
                excluded |= hit
        pins.sort(key=len)
        pool = pins[0] if pins else self.by_type[typ]
        return [c for c in pool if c in self.type_sets[typ] and c not in excluded
                and all(c in s for s in pins[1:])
                and all(self.holds(lit, {**binding, v: c}) for lit in slow)]

    def bind(self, action: Action) -> np.ndarray:
        """(n, arity) object ids of every binding of `action` whose static literals hold."""
        types = dict(action.parameters)
        params = list(types)
        lits = [lit for lit in action.precondition
                if lit.atom.predicate == "=" or lit.atom.predicate in self.facts]

        def var(lit: Literal) -> set[str]:
            return {a for a in lit.atom.args if a.startswith("?")}

        if not all(self.holds(lit, {}) for lit in lits if not var(lit)):
            return np.zeros((0, len(params)), np.int64)
        pending = [lit for lit in lits if var(lit)]
        order: list[str] = []
        while len(order) < len(params):  # greedy join order: most constrained first
            bound = set(order)

            def score(v: str, bound: set[str] = bound) -> tuple[int, int, bool, int]:
                mine = [lit for lit in pending if v in var(lit)]
                pinned = max((2 if lit.atom.predicate == "=" else 1 for lit in mine
                              if lit.positive and var(lit) - {v} <= bound), default=0)
                n_pos = sum(lit.positive for lit in mine)
                return -pinned, -n_pos, not mine, len(self.by_type[types[v]])

            order.append(min((v for v in params if v not in bound), key=score))
        checks = [[lit for lit in pending if v in var(lit) and var(lit) <= set(order[: d + 1])]
                  for d, v in enumerate(order)]
        free = len(order)  # order[free:] is unconstrained: expanded as a cartesian product
        while free and not checks[free - 1]:
            free -= 1
        prefixes: list[tuple[int, ...]] = []
        binding: dict[str, str] = {}

        def search(d: int) -> None:
            if d == free:
                prefixes.append(tuple(self.oid[binding[v]] for v in order[:free]))
                return
            for c in self.candidates(order[d], types[order[d]], checks[d], binding):
                binding[order[d]] = c
                search(d + 1)
            binding.pop(order[d], None)

        search(0)
        head = np.array(prefixes, np.int64).reshape(len(prefixes), free)
        tails = [np.array([self.oid[o] for o in self.by_type[types[v]]], np.int64)
                 for v in order[free:]]
        tail = (np.stack(np.meshgrid(*tails, indexing="ij"), -1).reshape(-1, len(tails))
                if tails else np.zeros((1, 0), np.int64))
        rows = np.concatenate([np.repeat(head, len(tail), 0), np.tile(tail, (len(head), 1))], 1)
        return rows[:, [order.index(v) for v in params]]


def ground(domain: Domain, problem: Problem, *, relevant_only: bool = False) -> GroundTask:
    """Ground `problem` over `domain` into a `GroundTask`.

    By default every ground action whose static preconditions (types, static predicates,
    ``=``, ``not =``) hold is kept, so the action set depends only on the objects and static
    facts, not on the fluent initial state. With ``relevant_only=True`` only actions reachable
    from the initial state under delete relaxation (negative preconditions ignored) are kept:
    often far fewer, but the action set, hence the ids, then depend on the initial state.
    (All actions are still instantiated first, so grounding itself is not faster.)
    """
    check_problem(domain, problem)
    fluent = domain.fluent_predicates()
    st = _Statics(domain, problem, fluent)
    preds = sorted(fluent)
    arity = max((len(domain.predicates[p]) for p in preds), default=0)
    base = len(st.names) + 1  # atom key: predicate, then each argument id + 1 (0 = none)
    if len(preds) * base**arity >= 2**62:
        raise PddlError(f"{problem.source}: too many objects ({len(st.names)}) to ground "
                        f"predicates of arity {arity}")

    def encode(pred: str, cols: Sequence[np.ndarray | int], n: int) -> np.ndarray:
        key = np.full(n, preds.index(pred), np.int64)
        for k in range(arity):
            key = key * base + (cols[k] + 1 if k < len(cols) else 0)
        return key

    def constant(lits: Sequence[Literal]) -> np.ndarray:
        return np.array([encode(lit.atom.predicate, [st.oid[x] for x in lit.atom.args], 1)[0]
                         for lit in lits], np.int64)

    labels: list[str] = []
    pairs: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {k: [] for k in _KINDS}
    for name in sorted(domain.actions):
        act = domain.actions[name]
        rows = st.bind(act)
        col = {v: k for k, (v, _) in enumerate(act.parameters)}
        lits = [lit for lit in act.precondition if lit.atom.predicate in fluent]
        for kind, atoms in (("pre", [lit.atom for lit in lits if lit.positive]),
                            ("neg", [lit.atom for lit in lits if not lit.positive]),
                            ("add", act.add_effects), ("dele", act.del_effects)):
            pairs[kind] += [(np.arange(len(labels), len(labels) + len(rows)), encode(
                atom.predicate, [rows[:, col[a]] if a in col else st.oid[a] for a in atom.args],
                len(rows))) for atom in atoms]
        names = np.array(st.names, object)[rows].tolist()
        labels += [f"({name} {' '.join(r)})" if r else f"({name})" for r in names]
    flat = {k: tuple(np.concatenate([p[j] for p in v] or [np.zeros(0, np.int64)])
                     for j in (0, 1)) for k, v in pairs.items()}
    init = constant([Literal(a) for a in problem.init if a.predicate in fluent])
    goal = [lit for lit in problem.goal if lit.atom.predicate in fluent]
    parts = [init, constant(goal)] + [flat[k][1] for k in _KINDS]
    keys, inv = _unique(np.concatenate(parts))
    init, goal_ids, *ids = np.split(inv, np.cumsum([len(p) for p in parts])[:-1])
    flat = {k: (flat[k][0], i) for k, i in zip(_KINDS, ids, strict=True)}
    add_keys = _unique(flat["add"][0] * len(keys) + flat["add"][1], inverse=False)[0]
    del_keys = flat["dele"][0] * len(keys) + flat["dele"][1]
    at = np.minimum(np.searchsorted(add_keys, del_keys), max(len(add_keys) - 1, 0))
    keep_del = add_keys[at] != del_keys if len(add_keys) else np.ones(len(del_keys), bool)
    flat["dele"] = (flat["dele"][0][keep_del], flat["dele"][1][keep_del])
    keep = (_relaxed(flat, init, len(labels), len(keys)) if relevant_only
            else np.ones(len(labels), bool))
    order = sorted(np.flatnonzero(keep).tolist(), key=labels.__getitem__)
    new_row = np.full(len(labels), -1, np.int64)
    new_row[order] = np.arange(len(order))
    flat = {k: (new_row[r][keep[r]], a[keep[r]]) for k, (r, a) in flat.items()}
    used = np.zeros(len(keys), bool)
    used[np.concatenate([init, goal_ids, *(a for _, a in flat.values())])] = True
    used_ids = np.flatnonzero(used)
    digits = keys[used_ids, None] // base ** np.arange(arity, -1, -1) % base
    digits[:, 0] = keys[used_ids] // base**arity
    text = [[preds[p], *(st.names[d - 1] for d in ds if d)] for p, *ds in digits.tolist()]
    atom_order = sorted(range(len(text)), key=lambda u: "(" + " ".join(text[u]) + ")")
    new_atom = np.full(len(keys), -1, np.int64)
    new_atom[used_ids[atom_order]] = np.arange(len(atom_order))
    n_atoms, n_actions = len(atom_order), len(order)
    csr = MappingProxyType({k: _csr(r, new_atom[a], n_actions, max(n_atoms, 1))
                            for k, (r, a) in flat.items()})
    state = np.zeros(n_atoms, bool)
    state[new_atom[init]] = True
    signs = np.array([lit.positive for lit in goal], bool)
    spell = domain.spelling
    return GroundTask(
        atoms=tuple("(" + " ".join(text[u]) + ")" for u in atom_order),
        actions=tuple(labels[i] for i in order),
        labels=tuple("(" + " ".join([spell.get(text[u][0], text[u][0]), *text[u][1:]]) + ")"
                     for u in atom_order),
        init=_ro(state), csr=csr, literals=_literals(csr, n_atoms),
        goal_pos=_ro(new_atom[goal_ids[signs]]), goal_neg=_ro(new_atom[goal_ids[~signs]]),
        goal_possible=all(st.holds(lit, {}) for lit in problem.goal
                          if lit.atom.predicate not in fluent))


def _relaxed(flat: Mapping[str, tuple[np.ndarray, np.ndarray]], init: np.ndarray,
             n_actions: int, n_atoms: int) -> np.ndarray:
    """Actions reachable from `init` ignoring delete effects and negative preconditions."""
    reached = np.zeros(n_atoms, bool)
    reached[init] = True
    (pre_r, pre_a), (add_r, add_a) = flat["pre"], flat["add"]
    while True:
        app = np.bincount(pre_r[~reached[pre_a]], minlength=n_actions) == 0
        new = reached.copy()
        new[add_a[app[add_r]]] = True
        if (new == reached).all():
            return app
        reached = new


def _literals(csr: Mapping[str, _CSR], n_atoms: int) -> _CSR:
    """Per action, ids into [state, ~state, True]; a dummy True if it has no precondition."""
    (pp, pf), (qp, qf) = csr["pre"], csr["neg"]
    rows = np.arange(len(pp) - 1)
    none = rows[(np.diff(pp) + np.diff(qp)) == 0]
    acts = np.concatenate([np.repeat(rows, np.diff(pp)), np.repeat(rows, np.diff(qp)), none])
    ids = np.concatenate([pf, qf + n_atoms, np.full(len(none), 2 * n_atoms)])
    o = np.argsort(acts, kind="stable")
    return _ro(np.searchsorted(acts[o], rows)), _ro(ids[o])
