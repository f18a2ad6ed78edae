"""Ground STRIPS -> Fast Downward SAS.

Used by the fast planning path: our relaxed-reachability grounder plus this writer
replace Fast Downward's Python translator. Atoms that no reachable action changes are
constants: actions needing them otherwise are dropped, and conditions on them vanish.

Multi-valued variables come from cheap "exactly one" invariants: atoms sharing a
predicate and all arguments but the last (``oc on slot1 ?x``: what stands on slot1;
``oc in hand ?x``: what the hand holds) form one variable when exactly one of them is
true initially and every action that makes one true makes another false (which it
requires). The remaining atoms get a binary variable each. Fewer, richer variables give
lama's landmark heuristic more to work with: plans get shorter.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Sequence

from utamp_gym.symbolic.pddl import Atom, Literal
from utamp_gym.symbolic.reach import GroundOp


def _name(a: Atom) -> str:
    return f"{a.predicate}({', '.join(a.args)})"


def _exactly_one_groups(
    ops: Sequence[GroundOp], init: set[Atom], changing: set[Atom], goal: Sequence[Literal]
) -> list[list[Atom]]:
    candidates: dict[tuple[str, tuple[str, ...]], list[Atom]] = defaultdict(list)
    for a in changing:
        if a.args:
            candidates[(a.predicate, a.args[:-1])].append(a)
    negated = {a for op in ops for a in op.pre_neg} | {lit.atom for lit in goal if not lit.positive}
    groups = []
    for atoms in candidates.values():
        members = set(atoms)
        if len(atoms) < 2 or members & negated or len(members & init) != 1:
            continue
        ok = True
        for op in ops:
            made = [a for a in op.add if a in members and a not in op.pre]
            lost = [a for a in op.delete if a in members and a not in op.add]
            if len(made) != len(lost) or len(made) > 1 or any(a not in op.pre for a in lost):
                ok = False
                break
        if ok:
            groups.append(sorted(atoms, key=lambda a: a.args))
    return sorted(groups, key=lambda g: (g[0].predicate, g[0].args))


def to_sas(ops: Sequence[GroundOp], init: Iterable[Atom], goal: Sequence[Literal]) -> str | None:
    """SAS text of the task, or None when a goal literal can never hold (unsolvable)."""
    init_set = set(init)
    changing: set[Atom] = set()
    for op in ops:
        changing.update(op.add)
        changing.update(op.delete)

    def const_ok(atom: Atom, want: bool) -> bool:
        return (atom in init_set) == want

    kept = [
        op
        for op in ops
        if all(a in changing or const_ok(a, True) for a in op.pre)
        and all(a in changing or const_ok(a, False) for a in op.pre_neg)
    ]
    goal_lits: list[tuple[Atom, bool]] = []
    for lit in goal:
        if lit.atom in changing:
            goal_lits.append((lit.atom, lit.positive))
        elif not const_ok(lit.atom, lit.positive):
            return None

    # variables: (var, value when true, value when false or None for multi-valued)
    groups = _exactly_one_groups(kept, init_set, changing, goal)
    where: dict[Atom, tuple[int, int, int | None]] = {}
    out = ["begin_version", "3", "end_version", "begin_metric", "0", "end_metric"]
    var_lines: list[str] = []
    init_values: list[int] = []
    for g in groups:
        v = len(init_values)
        for k, a in enumerate(g):
            where[a] = (v, k, None)
        var_lines += ["begin_variable", f"var{v}", "-1", str(len(g))]
        var_lines += [f"Atom {_name(a)}" for a in g] + ["end_variable"]
        init_values.append(next(k for k, a in enumerate(g) if a in init_set))
    for a in sorted(changing - set(where), key=lambda a: (a.predicate, a.args)):
        v = len(init_values)
        where[a] = (v, 0, 1)
        var_lines += [
            "begin_variable",
            f"var{v}",
            "-1",
            "2",
            f"Atom {_name(a)}",
            f"NegatedAtom {_name(a)}",
            "end_variable",
        ]
        init_values.append(0 if a in init_set else 1)
    out += [str(len(init_values)), *var_lines, "0", "begin_state"]
    out += [str(x) for x in init_values]
    goal_vals = {
        where[a][0]: (where[a][1] if positive else where[a][2]) for a, positive in goal_lits
    }
    out += ["end_state", "begin_goal", str(len(goal_vals))]
    out += [f"{v} {val}" for v, val in sorted(goal_vals.items())]
    out += ["end_goal", str(len(kept))]
    for op in kept:
        pre: dict[int, int] = {}
        for a in op.pre:
            if a in where:
                pre[where[a][0]] = where[a][1]
        for a in op.pre_neg:
            if a in where:
                pre[where[a][0]] = where[a][2]  # binary variables only (groups exclude these)
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
        out += ["begin_operator", op.name, str(len(prevail))]
        out += [f"{v} {val}" for v, val in prevail]
        out.append(str(len(effects)))
        out += [f"0 {v} {p} {q}" for v, p, q in effects]
        out += ["1", "end_operator"]
    out.append("0")
    return "\n".join(out) + "\n"
