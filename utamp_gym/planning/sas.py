"""Ground STRIPS -> Fast Downward SAS (one binary variable per changing atom).

Used by the fast planning path: our relaxed-reachability grounder plus this writer
replace Fast Downward's Python translator. Atoms no reachable action changes are
constants: actions needing them otherwise are dropped, and conditions on them vanish.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from utamp_gym.symbolic.pddl import Atom, Literal
from utamp_gym.symbolic.reach import GroundOp


def _name(a: Atom) -> str:
    return f"{a.predicate}({', '.join(a.args)})"


def to_sas(ops: Sequence[GroundOp], init: Iterable[Atom], goal: Sequence[Literal]) -> str | None:
    """SAS text of the task, or None when a goal literal can never hold (unsolvable)."""
    init_set = set(init)
    changing: set[Atom] = set()
    for op in ops:
        changing.update(op.add)
        changing.update(op.delete)

    def const_ok(atom: Atom, want: bool) -> bool:
        return (atom in init_set) == want

    kept: list[GroundOp] = []
    for op in ops:
        if all(a in changing or const_ok(a, True) for a in op.pre) and all(
            a in changing or const_ok(a, False) for a in op.pre_neg
        ):
            kept.append(op)
    goal_conds: list[tuple[Atom, bool]] = []
    for lit in goal:
        if lit.atom in changing:
            goal_conds.append((lit.atom, lit.positive))
        elif not const_ok(lit.atom, lit.positive):
            return None
    variables = sorted(changing, key=lambda a: (a.predicate, a.args))
    index = {a: i for i, a in enumerate(variables)}

    out = [
        "begin_version",
        "3",
        "end_version",
        "begin_metric",
        "0",
        "end_metric",
        str(len(variables)),
    ]
    for i, a in enumerate(variables):
        out += [
            "begin_variable",
            f"var{i}",
            "-1",
            "2",
            f"Atom {_name(a)}",
            f"NegatedAtom {_name(a)}",
            "end_variable",
        ]
    out += ["0", "begin_state"]
    out += ["0" if a in init_set else "1" for a in variables]
    out += ["end_state", "begin_goal", str(len(goal_conds))]
    out += [f"{index[a]} {0 if positive else 1}" for a, positive in goal_conds]
    out += ["end_goal", str(len(kept))]
    for op in kept:
        pre = {index[a]: 0 for a in op.pre if a in index}
        pre.update({index[a]: 1 for a in op.pre_neg if a in index})
        post: dict[int, int] = {index[a]: 1 for a in op.delete}
        post.update({index[a]: 0 for a in op.add})  # add wins over delete
        effects = [(v, pre.get(v, -1), val) for v, val in sorted(post.items()) if pre.get(v) != val]
        prevail = [(v, val) for v, val in sorted(pre.items()) if v not in post or post[v] == val]
        out += ["begin_operator", op.name, str(len(prevail))]
        out += [f"{v} {val}" for v, val in prevail]
        out.append(str(len(effects)))
        out += [f"0 {v} {p} {q}" for v, p, q in effects]
        out += ["1", "end_operator"]
    out.append("0")
    return "\n".join(out) + "\n"
