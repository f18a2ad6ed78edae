"""Map a plan in the VLM's simplified vocabulary to full U-TAMP-2 actions.

``pick ?obj1 ?obj2`` -> ``pick-support``, ``place ?obj1 ?obj2`` -> ``place-support`` and
``slide ?obj1 ?space`` -> ``slide-support``; the remaining parameters (member, grasp
parts, bases, forces, contact parts) are chosen by the mapper. Steps are mapped in
order while the symbolic state is tracked: every non-affordance precondition (the
hand, contacts, workspace, orientation) must hold, otherwise the step cannot be mapped
and the mapping stops there. Among the bindings that satisfy those, the mapper takes
one that violates the fewest ground-truth affordance preconditions (of the domain mapped
in: U-TAMP-2, or the extended ``utamp2x`` on procedural-v2) (a valid one when
there is one), so validating the mapped plan afterwards names the affordance the VLM
got wrong. Names: detected kinds (``glass-mug``), the numbered kinds the prompt gives
objects that share a kind (``glass-mug-1``, `answer_names`) or scene names (``mug``);
``table`` for the table top (a free slot is chosen), ``space`` for any free space.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

from utamp_gym.affordances.facts import PREDICATES
from utamp_gym.affordances.sources import ground_truth_for
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.pddl import Atom, Domain, Literal, parse_domain, parse_problem
from utamp_gym.symbolic.problem import build_problem, domain_text
from utamp_gym.symbolic.validate import holds

VERBS = {"pick": "pick-support", "place": "place-support", "slide": "slide-support"}
TABLE_NAMES = ("table", "kitchen-table", "table-top")
SPACE_NAMES = ("space", "free-space", "empty-space")

#: the affordance predicates, as the parsed PDDL spells them (lower case)
AFFORDANCE_PREDICATES = frozenset(p.lower() for p in PREDICATES)


@dataclass(frozen=True)
class MappedPlan:
    """Full actions for the mapped prefix; `error` says why the next step was not mapped."""

    actions: tuple[str, ...]
    error: str | None = None

    @property
    def complete(self) -> bool:
        return self.error is None


def answer_names(scene: Scene) -> dict[str, str]:
    """Object -> the name an answer uses for it: its kind (type), as the detection question
    asks; objects that share a kind get the kind and their number among those objects, in
    the scene's order (``glass-mug-1``, ``glass-mug-2``: the prompt says which is which)."""
    kinds = Counter(o.type for o in scene.objects)
    seen: Counter[str] = Counter()
    names = {}
    for o in scene.objects:
        seen[o.type] += 1
        names[o.name] = o.type if kinds[o.type] == 1 else f"{o.type}-{seen[o.type]}"
    return names


def _norm(token: str) -> str:
    return re.sub(r"[\s_]+", "-", token.strip().strip("'\"").lower())


def split_step(step: object) -> list[str]:
    """``"(pick glass-mug table)"``, ``"pick glass_mug, table"`` or a list -> tokens."""
    if isinstance(step, list | tuple):
        return [_norm(str(t)) for t in step if str(t).strip()]
    text = re.sub(r"[(),]", " ", str(step))
    return [_norm(t) for t in text.split()]


class PlanMapper:
    """Maps simplified steps of one scene against its ground-truth U-TAMP-2 problem."""

    def __init__(self, scene: Scene, domain: str = "utamp2"):
        self.scene = scene
        self.domain: Domain = parse_domain(domain_text(domain), source=f"{domain}.pddl")
        truth = ground_truth_for(scene, domain)
        problem = parse_problem(build_problem(scene, truth, domain).text, source=scene.name)
        self.state: set[Atom] = set(problem.init)
        self.objects = sorted(
            [*problem.objects, *(c for c, t in self.domain.constants.items() if t == "obj")]
        )
        self.parts = sorted(c for c, t in self.domain.constants.items() if t == "part")
        self.slots = [s.name for s in scene.slots]
        self.spaces = [s.name for s in scene.spaces]
        self.numbered = {  # the names the prompt gives objects that share a kind
            _norm(n): o for o, n in answer_names(scene).items() if n != scene.object(o).type
        }

    def resolve(self, name: str, *, space: bool = False) -> list[str]:
        """Scene symbols a name may denote (empty if unknown)."""
        if space:
            if name in SPACE_NAMES:
                return list(self.spaces)
            return [name] if name in self.spaces else []
        if name in TABLE_NAMES:
            return list(self.slots)
        if name in self.numbered:
            return [self.numbered[name]]
        hits = [o.name for o in self.scene.objects if name in (o.name, o.type)]
        return hits or ([name] if name in self.slots else [])

    def map_step(self, step: object) -> str:
        """The full action for one simplified step (applied to the state); ValueError if none."""
        tokens = split_step(step)
        if len(tokens) != 3 or tokens[0].removesuffix("-support") not in VERBS:
            raise ValueError("expected 'pick|place ?obj1 ?obj2' or 'slide ?obj1 ?space'")
        verb = tokens[0].removesuffix("-support")
        action = self.domain.actions[VERBS[verb]]
        fixed: dict[str, list[str]] = {"?obj1": self.resolve(tokens[1])}
        second = "?space" if verb == "slide" else "?obj2"
        fixed[second] = self.resolve(tokens[2], space=verb == "slide")
        for var, tok in (("?obj1", tokens[1]), (second, tokens[2])):
            if not fixed[var]:
                raise ValueError(f"unknown object '{tok}'")
        self._blocker, self._depth = "no binding", -1
        best = self._bind(action.parameters, action.precondition, fixed)
        if best is None:
            raise ValueError(f"not applicable: {self._blocker}")
        args = tuple(best[v] for v, _ in action.parameters)
        _, add, delete = action.instantiate(args)
        self.state.difference_update(delete)
        self.state.update(add)
        return "(" + " ".join((action.name, *args)) + ")"

    def _bind(
        self,
        params: Sequence[tuple[str, str]],
        pre: Sequence[Literal],
        fixed: dict[str, list[str]],
    ) -> dict[str, str] | None:
        """A binding satisfying all hard literals with the fewest soft (affordance) violations."""
        order = [v for v, _ in params]
        domains = {
            v: fixed.get(v) or (self.parts if t == "part" else self.objects) for v, t in params
        }
        ready: dict[str, list[Literal]] = {v: [] for v in order}
        for lit in pre:
            vars_ = [a for a in lit.atom.args if a.startswith("?")]
            last = max((order.index(a) for a in vars_), default=0)
            ready[order[last]].append(lit)
        best: list[tuple[int, dict[str, str]]] = []

        def ground(lit: Literal, binding: dict[str, str]) -> Literal:
            return Literal(
                Atom(lit.atom.predicate, tuple(binding.get(a, a) for a in lit.atom.args)),
                lit.positive,
            )

        def rec(i: int, binding: dict[str, str], violations: int) -> None:
            if best and (best[0][0] == 0 or violations >= best[0][0]):
                return  # a valid binding is known, or this one is no better
            if i == len(order):
                best[:] = [(violations, dict(binding))]
                return
            var = order[i]
            for value in domains[var]:
                binding[var] = value
                v, ok = violations, True
                for lit in ready[var]:
                    g = ground(lit, binding)
                    if holds(g, self.state):
                        continue
                    if lit.atom.predicate in AFFORDANCE_PREDICATES:
                        v += 1
                        continue
                    ok = False
                    if i > self._depth:  # report the hard literal that blocked deepest
                        self._blocker, self._depth = f"{self.domain.show(g)} is false", i
                    break
                if ok:
                    rec(i + 1, binding, v)
                del binding[var]

        rec(0, {}, 0)
        return best[0][1] if best else None


def map_plan(scene: Scene, steps: Sequence[object], domain: str = "utamp2") -> MappedPlan:
    """Map `steps` in order; stops at the first step that cannot be mapped. `domain`: whose
    ground truth ranks the bindings (``utamp2x`` on procedural-v2, its labels' domain)."""
    mapper = PlanMapper(scene, domain)
    actions: list[str] = []
    for k, step in enumerate(steps, 1):
        try:
            actions.append(mapper.map_step(step))
        except ValueError as exc:
            return MappedPlan(tuple(actions), f"step {k} {step!r}: {exc}")
    return MappedPlan(tuple(actions))
