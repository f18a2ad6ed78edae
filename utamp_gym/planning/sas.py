"""Ground STRIPS -> Fast Downward SAS.

Used by the fast planning path: our relaxed-reachability grounder plus this writer
replace Fast Downward's Python translator. Atoms that no reachable action changes are
constants: actions needing them otherwise are dropped, and conditions on them vanish.

Multi-valued variables come from cheap "exactly one" invariants: atoms sharing a
predicate and all arguments but the last (``oc on slot1 ?x``: what stands on slot1;
``oc in hand ?x``: what the hand holds) form one variable when exactly one of them is
true initially and every action that makes one true makes another false (which it
requires). The remaining atoms get a binary variable each. Fewer, richer variables give
the search's heuristics more to work with.

`build_sas` returns a `SasTask`: everything but the initial state, written once, so that a
planner can re-plan from another state by writing only that state (`SasTask.text`), after
`SasTask.covers` confirmed the task is valid for it.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Collection, Iterable, Mapping, Sequence
from types import MappingProxyType

from utamp_gym.deadline import Deadline
from utamp_gym.symbolic.pddl import Atom, Literal
from utamp_gym.symbolic.reach import GroundOp


def _name(a: Atom) -> str:
    return f"{a.predicate}({', '.join(a.args)})"


def _exactly_one_groups(
    ops: Sequence[GroundOp], init: set[Atom], changing: set[Atom], goal: Sequence[Literal]
) -> list[list[Atom]]:
    """Candidate groups (atoms sharing all arguments but the last) that are exactly-one
    invariants; each is checked only against the operators that touch it."""
    candidates: dict[tuple[str, tuple[str, ...]], set[Atom]] = defaultdict(set)
    for a in changing:
        if a.args:
            candidates[(a.predicate, a.args[:-1])].add(a)
    negated = {a for op in ops for a in op.pre_neg} | {lit.atom for lit in goal if not lit.positive}
    ok = {
        key
        for key, members in candidates.items()
        if len(members) >= 2 and not members & negated and len(members & init) == 1
    }
    touching: dict[tuple[str, tuple[str, ...]], list[GroundOp]] = defaultdict(list)
    for op in ops:
        keys = {(a.predicate, a.args[:-1]) for a in (*op.add, *op.delete) if a.args}
        for key in keys & ok:
            touching[key].append(op)
    groups = []
    for key in ok:
        members = candidates[key]
        for op in touching[key]:
            made = [a for a in op.add if a in members and a not in op.pre]
            lost = [a for a in op.delete if a in members and a not in op.add]
            if len(made) != len(lost) or len(made) > 1 or any(a not in op.pre for a in lost):
                break
        else:
            groups.append(sorted(members, key=lambda a: a.args))
    return sorted(groups, key=lambda g: (g[0].predicate, g[0].args))


_SAS_FIELDS = (
    "ops",
    "op_index",
    "variables",
    "n_groups",
    "group_of",
    "changing",
    "fixed",
    "head",
    "goal",
    "operators",
    "solvable",
)


class SasTask:
    """A SAS task without its initial state (see the module docstring).

    `variables[v]` lists the atoms of variable v: for the first `n_groups`, the values of a
    multi-valued variable (exactly one is true); after them, one atom per binary variable
    (value 0: true, 1: false). `changing` holds the atoms some operator changes, `fixed` the
    atoms that were true initially and that no operator changes. If `solvable` is False a
    goal literal can never hold (an atom outside `changing` has the wrong value) and the
    task has no text. Immutable; compared by identity.
    """

    __slots__ = _SAS_FIELDS

    ops: tuple[GroundOp, ...]
    op_index: Mapping[str, int]
    variables: tuple[tuple[Atom, ...], ...]
    n_groups: int
    group_of: Mapping[Atom, tuple[int, int]]  # atom of a multi-valued variable -> (var, value)
    changing: frozenset[Atom]
    fixed: frozenset[Atom]
    head: str
    goal: str
    operators: tuple[str, ...]
    solvable: bool

    def __init__(
        self,
        ops: tuple[GroundOp, ...],
        op_index: Mapping[str, int],
        variables: tuple[tuple[Atom, ...], ...],
        n_groups: int,
        group_of: Mapping[Atom, tuple[int, int]],
        changing: frozenset[Atom],
        fixed: frozenset[Atom],
        head: str,
        goal: str,
        operators: tuple[str, ...],
        solvable: bool = True,
    ) -> None:
        set_field = object.__setattr__  # the instance is immutable once built
        set_field(self, "ops", ops)
        set_field(self, "op_index", op_index)
        set_field(self, "variables", variables)
        set_field(self, "n_groups", n_groups)
        set_field(self, "group_of", group_of)
        set_field(self, "changing", changing)
        set_field(self, "fixed", fixed)
        set_field(self, "head", head)
        set_field(self, "goal", goal)
        set_field(self, "operators", operators)
        set_field(self, "solvable", solvable)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"cannot assign to field {name!r}: a SasTask is immutable")

    def __repr__(self) -> str:
        return (
            f"SasTask({len(self.ops)} operators, {len(self.variables)} variables, "
            f"solvable={self.solvable})"
        )

    def __reduce__(self) -> tuple[type[SasTask], tuple[object, ...]]:
        return SasTask, tuple(getattr(self, name) for name in _SAS_FIELDS)

    def covers(self, state: Collection[Atom], fixed: Collection[Atom] | None = None) -> str | None:
        """Why this task cannot be used from `state` (None if it can).

        Valid when `state` agrees with the task on the atoms no operator changes (`fixed`:
        the part of `self.fixed` that can differ between states, default all of it) and
        each multi-valued variable has exactly one true value. Atoms outside `changing`
        and `fixed` (e.g. not reachable from the state the task was grounded for) fail it.
        """
        fixed = self.fixed if fixed is None else fixed
        outside = [a for a in state if a not in self.changing]
        if len(outside) != len(fixed) or any(a not in fixed for a in outside):
            extra = next((a for a in outside if a not in fixed), None)
            what = f"{extra} is not" if extra else "an atom that no action changes is no longer"
            return f"{what} in the grounded task"
        counts = [0] * self.n_groups
        for a in state:
            hit = self.group_of.get(a)
            if hit is not None:
                counts[hit[0]] += 1
        bad = next((v for v, c in enumerate(counts) if c != 1), None)
        if bad is not None:
            return f"{counts[bad]} atoms of the exactly-one group of {self.variables[bad][0]} hold"
        return None

    def initial_values(self, state: Collection[Atom]) -> list[int]:
        """The value of each variable in `state` (which `covers` accepted)."""
        out = [0] * len(self.variables)
        for a in state:
            hit = self.group_of.get(a)
            if hit is not None:
                out[hit[0]] = hit[1]
        for v in range(self.n_groups, len(self.variables)):
            out[v] = 0 if self.variables[v][0] in state else 1
        return out

    def text(self, state: Collection[Atom], exclude: Collection[int] = ()) -> str:
        """SAS text from `state`, without the operators whose indexes are in `exclude`."""
        ops = self.operators
        if exclude:
            ops = tuple(o for i, o in enumerate(ops) if i not in exclude)
        values = "\n".join(map(str, self.initial_values(state)))
        return "".join((self.head, values, "\n", self.goal, str(len(ops)), "\n", *ops, "0\n"))


def build_sas(
    ops: Sequence[GroundOp],
    init: Iterable[Atom],
    goal: Sequence[Literal],
    deadline: Deadline | None = None,
) -> SasTask:
    """The SAS task of `ops` from `init` (`solvable` False if a goal literal can never hold,
    or two goal literals contradict each other: an atom and its negation, or two values of
    one multi-valued variable).

    Raises `PlanningTimeout` (phase ``sas``) once `deadline` passes.
    """
    init_set = set(init)
    changing: set[Atom] = set()
    for op in ops:
        changing.update(op.add)
        changing.update(op.delete)
    fixed = frozenset(init_set - changing)

    kept = [
        op
        for op in ops
        if all(a in changing or a in init_set for a in op.pre)
        and not any(a not in changing and a in init_set for a in op.pre_neg)
    ]
    empty = MappingProxyType({})
    unsolvable = SasTask((), empty, (), 0, empty, frozenset(changing), fixed, "", "", (), False)
    goal_lits: dict[Atom, bool] = {}
    for lit in goal:
        if lit.atom in changing:
            if goal_lits.setdefault(lit.atom, lit.positive) != lit.positive:
                return unsolvable  # the goal asks for an atom and its negation
        elif (lit.atom in init_set) != lit.positive:
            return unsolvable
    if deadline is not None:
        deadline.check("sas")

    groups = _exactly_one_groups(kept, init_set, changing, goal)
    if deadline is not None:
        deadline.check("sas")
    in_group = {a for g in groups for a in g}
    binary = sorted(changing - in_group, key=lambda a: (a.predicate, a.args))
    variables = (*map(tuple, groups), *((a,) for a in binary))
    where: dict[Atom, tuple[int, int, int | None]] = {}
    lines = ["begin_version", "3", "end_version", "begin_metric", "0", "end_metric"]
    lines.append(str(len(variables)))
    for v, atoms in enumerate(variables):
        if v < len(groups):
            for k, a in enumerate(atoms):
                where[a] = (v, k, None)
            lines += ["begin_variable", f"var{v}", "-1", str(len(atoms))]
            lines += [f"Atom {_name(a)}" for a in atoms] + ["end_variable"]
        else:
            (a,) = atoms
            where[a] = (v, 0, 1)
            lines += ["begin_variable", f"var{v}", "-1", "2", f"Atom {_name(a)}"]
            lines += [f"NegatedAtom {_name(a)}", "end_variable"]
    lines += ["0", "begin_state", ""]
    goal_vals: dict[int, int] = {}
    for a, positive in goal_lits.items():
        v, true_value, false_value = where[a]
        value = true_value if positive else false_value
        assert value is not None  # negated goal atoms are never in a multi-valued variable
        if goal_vals.setdefault(v, value) != value:
            # two values of one variable (e.g. two things on one slot): never both true
            return unsolvable
    goal_text = ["end_state", "begin_goal", str(len(goal_vals))]
    goal_text += [f"{v} {val}" for v, val in sorted(goal_vals.items())] + ["end_goal", ""]
    blocks = []
    for op in kept:
        pre: dict[int, int] = {}
        for a in op.pre:
            if a in where:
                pre[where[a][0]] = where[a][1]
        for a in op.pre_neg:
            if a in where:
                pre[where[a][0]] = where[a][2]  # type: ignore[assignment]  # binary only
        post: dict[int, int] = {}
        for a in op.delete:
            v, _, false_value = where[a]
            if false_value is not None:
                post[v] = false_value
        for a in op.add:  # add wins over delete
            v, true_value, _ = where[a]
            post[v] = true_value
        effects = [(v, pre.get(v, -1), val) for v, val in sorted(post.items()) if pre.get(v) != val]
        prevail = [(v, val) for v, val in sorted(pre.items()) if v not in post or post[v] == val]
        block = ["begin_operator", op.name, str(len(prevail))]
        block += [f"{v} {val}" for v, val in prevail]
        block.append(str(len(effects)))
        block += [f"0 {v} {p} {q}" for v, p, q in effects]
        block += ["1", "end_operator", ""]
        blocks.append("\n".join(block))
    return SasTask(
        ops=tuple(kept),
        op_index=MappingProxyType({op.name: i for i, op in enumerate(kept)}),
        variables=variables,
        n_groups=len(groups),
        group_of=MappingProxyType({a: (v, k) for a, (v, k, f) in where.items() if f is None}),
        changing=frozenset(changing),
        fixed=fixed,
        head="\n".join(lines),
        goal="\n".join(goal_text),
        operators=tuple(blocks),
    )


def to_sas(ops: Sequence[GroundOp], init: Iterable[Atom], goal: Sequence[Literal]) -> str | None:
    """SAS text of the task, or None when a goal literal can never hold (unsolvable)."""
    init = set(init)
    task = build_sas(ops, init, goal)
    return task.text(init) if task.solvable else None


__all__ = ["SasTask", "build_sas", "to_sas"]
