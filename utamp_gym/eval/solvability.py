"""Fast repeated solvability checks of one scene under varying affordance facts.

Explanations ask "is the scene solvable with these facts?" for many fact sets that
differ only in static affordance atoms. Grounding dominates a planner call, so the
scene is grounded once, under the union of all candidate facts, and every check
just filters the ground actions whose affordance preconditions hold, then runs a
delete-relaxed reachability test and, only if that passes, the Fast Downward search.

Negative static preconditions (``not canLift``) would make the union grounding drop
actions, so they are rewritten as positive ``not-canlift`` atoms that hold for every
tuple in the union and, per check, exactly when the positive fact is absent.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
from collections.abc import Iterable

from utamp_gym.affordances.facts import Fact
from utamp_gym.errors import PlanningError
from utamp_gym.planning.fast_downward import downward_paths
from utamp_gym.planning.sas import to_sas
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.pddl import Atom, Domain, Literal, Problem, parse_domain, parse_problem
from utamp_gym.symbolic.problem import build_problem, domain_text, instantiate_affordances
from utamp_gym.symbolic.reach import GroundOp, reachable_ops

AFFORDANCE_PREDICATES = frozenset(
    {"issupportive", "issupportable", "isp2psupportive", "cangraspfrom", "canlift", "canslide"}
)
NOT = "not-"
SEARCH = ("--search", "let(h,ff(),lazy_greedy([h],preferred=[h],cost_type=one))")
UNSOLVABLE_CODES = (11, 12)


def _atom(text: str) -> Atom:
    """``(isP2PSupportive on a under b)`` -> Atom with the lower-case predicate."""
    pred, *args = text.strip("()").split()
    return Atom(pred.lower(), tuple(args))


def _positive_domain(domain: Domain) -> Domain:
    """`domain` with each negated affordance precondition ``(not (p x))`` as ``(not-p x)``."""
    actions = {}
    predicates = dict(domain.predicates)
    for name, act in domain.actions.items():
        pre = []
        for lit in act.precondition:
            if not lit.positive and lit.atom.predicate in AFFORDANCE_PREDICATES:
                neg = NOT + lit.atom.predicate
                predicates[neg] = domain.predicates[lit.atom.predicate]
                pre.append(Literal(Atom(neg, lit.atom.args)))
            else:
                pre.append(lit)
        actions[name] = act._replace(precondition=tuple(pre))
    return domain._replace(actions=actions, predicates=predicates)


class SolvabilityOracle:
    """``oracle(facts)``: is `scene` solvable in `domain` (U-TAMP-2 or its extended
    ``utamp2x``) with these type-level facts?

    Every `facts` passed in must be a subset of `union` (the facts grounded once).
    """

    def __init__(
        self,
        scene: Scene,
        union: Iterable[Fact],
        *,
        timeout: float = 5.0,
        domain: str = "utamp2",
    ):
        self.scene, self.timeout, self.domain = scene, timeout, domain
        self.union = frozenset(union)
        pddl = _positive_domain(parse_domain(domain_text(domain), source=f"{domain}.pddl"))
        problem = parse_problem(build_problem(scene, self.union, domain).text, source=scene.name)
        negated = {p[len(NOT) :] for p in pddl.predicates if p.startswith(NOT)}
        everything = [*problem.objects, *(c for c, t in pddl.constants.items() if t == "obj")]
        extra = {Atom(NOT + p, (a, b)) for p in negated for a in everything for b in everything}
        self.problem: Problem = problem._replace(init=problem.init | extra)
        ops, _, _ = reachable_ops(pddl, self.problem)
        wanted = AFFORDANCE_PREDICATES | {NOT + p for p in negated}
        self.ops: list[tuple[GroundOp, tuple[Atom, ...]]] = []
        for op in ops:
            name, *args = op.name.split()
            pre, _, _ = pddl.actions[name].instantiate(args)
            self.ops.append((op, tuple(lit.atom for lit in pre if lit.atom.predicate in wanted)))
        self.checks = 0

    def allowed(self, facts: Iterable[Fact]) -> list[GroundOp]:
        """The ground actions whose affordance preconditions hold under `facts`."""
        atoms = {_atom(a) for a in instantiate_affordances(self.scene, facts)}

        def holds(a: Atom) -> bool:
            if a.predicate.startswith(NOT):
                return Atom(a.predicate[len(NOT) :], a.args) not in atoms
            return a in atoms

        return [op for op, needs in self.ops if all(map(holds, needs))]

    @property
    def goal(self) -> tuple[str, ...]:
        """The problem's goal atoms as text, ``(oc on slot2 air)``."""
        return tuple(_text(lit.atom) for lit in self.problem.goal)

    def __call__(self, facts: Iterable[Fact], goal: Iterable[str] | None = None) -> bool:
        """Solvable under `facts`? `goal`: only these of the problem's goal atoms (`goal`)."""
        facts = frozenset(facts)
        if not facts <= self.union:
            raise ValueError("facts outside the grounded union")
        literals = self.problem.goal
        if goal is not None:
            wanted = set(goal)
            if not wanted <= set(self.goal):
                raise ValueError(
                    f"not goal atoms of the problem: {sorted(wanted - set(self.goal))}"
                )
            literals = tuple(lit for lit in literals if _text(lit.atom) in wanted)
        self.checks += 1
        positive = [lit.atom for lit in literals if lit.positive]
        init = self.problem.init
        if all((lit.atom in init) == lit.positive for lit in literals):
            return True  # the goal holds already (Fast Downward refuses a task without variables)
        ops = self.allowed(facts)
        if not _relaxed_reachable(ops, self.problem.init, positive):
            return False
        sas = to_sas(ops, self.problem.init, literals)
        return sas is not None and _search(sas, self.timeout)


def _text(atom: Atom) -> str:
    return f"({' '.join((atom.predicate, *atom.args))})"


def _relaxed_reachable(ops: list[GroundOp], init: Iterable[Atom], goal: list[Atom]) -> bool:
    """Delete-relaxed reachability of the positive goal atoms (a necessary condition)."""
    reached = set(init)
    pending = list(ops)
    changed = True
    while changed:
        changed, rest = False, []
        for op in pending:
            if all(a in reached for a in op.pre):
                reached.update(op.add)
                changed = True
            else:
                rest.append(op)
        pending = rest
    return all(a in reached for a in goal)


def _search(sas: str, timeout: float) -> bool:
    """Run the search binary on `sas`: True if it finds a plan, False if none (or time-out)."""
    binary, _ = downward_paths()
    with tempfile.TemporaryDirectory(prefix="utamp_explain_") as tmp:
        path = os.path.join(tmp, "output.sas")
        with open(path, "w") as f:
            f.write(sas)
        cmd = [str(binary), *SEARCH, "--internal-plan-file", "sas_plan"]
        try:
            with open(path, "rb") as stdin:
                proc = subprocess.run(
                    cmd, cwd=tmp, stdin=stdin, capture_output=True, timeout=timeout, check=False
                )
        except subprocess.TimeoutExpired:
            return False
    if proc.returncode == 0:
        return True
    if proc.returncode in UNSOLVABLE_CODES:
        return False
    tail = (proc.stderr or proc.stdout).decode(errors="replace")[-500:]
    raise PlanningError(f"Fast Downward search failed with exit code {proc.returncode}: {tail}")
