"""Why-not explanations: which affordance facts block a scene that is unsolvable as detected.

Given the detected facts D and the ground truth G, the candidate corrections are the
missing facts (G − D, to add) and the spurious facts of predicates the domain uses
negatively (D − G with ``canLift``: an object wrongly believed liftable cannot be
slid). Subsets of corrections are tried by increasing size, each checked by planning
with a short time-out (the planner proves most unsolvable tasks in-process by relaxed
reachability, so a check costs milliseconds to tens of milliseconds); the first subset
that makes the task solvable is a smallest one. Checks share one grounding (see
`solvability`). Since adding facts only enables actions, a missing fact without
which even the full ground truth is unsolvable belongs to every solution: these are
found first (one check each) and the search only tries the others on top. When the
size or time budget runs out, a minimal (irreducible, not necessarily smallest) set is
found by deleting corrections from the full set one by one.

When even the ground truth leaves the scene unsolvable, no correction helps: the
explanation then names the goal atoms the ground truth blocks and, for each, the rule that
refuses with its numbers (`utamp_gym.eval.blocking`).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.sources import (
    DEFAULT_NOISE,
    affordances_for,
    detection_rng,
    ground_truth_for,
)
from utamp_gym.eval.blocking import Block, blocking_goals, format_fact
from utamp_gym.eval.solvability import SolvabilityOracle
from utamp_gym.planning.methods import method_spec
from utamp_gym.scene.model import Scene

#: the domains with affordances (U-TAMP-1 has none to correct)
EXPLAINED_DOMAINS = ("utamp2", "utamp2x")
NEGATIVELY_USED = ("canLift",)  # affordance predicates under `not` in utamp2.pddl
Change = tuple[str, Fact]  # ("+", fact) to add, ("-", fact) to remove
NO_CORRECTION = "no set of ground-truth affordance corrections makes the scene solvable"


@dataclass(frozen=True)
class Explanation:
    """Corrections that make an unsolvable scene solvable.

    `found` is False when even the ground truth does not make it solvable (or no set was
    found in the budget); `smallest` is True when the search by size proved minimum size.
    `blocking` then names why the ground truth itself is unsolvable (`blocking_goals`), and
    `rest_solvable` whether the goal without the blocked atoms is solvable (None: not
    checked).
    """

    scene: str
    found: bool
    missing: tuple[Fact, ...]
    spurious: tuple[Fact, ...]
    smallest: bool
    checks: int
    elapsed_s: float
    blocking: tuple[Block, ...] = ()
    rest_solvable: bool | None = None

    @property
    def blocked_atoms(self) -> tuple[str, ...]:
        """The goal atoms the ground truth blocks (in the order of the scene's objects)."""
        return tuple(dict.fromkeys(b.atom for b in self.blocking))

    @property
    def headline(self) -> str:
        """The message without the blocks' reasons."""
        if self.found or not self.blocking:
            return self.message
        atoms = self.blocked_atoms
        head = f"{NO_CORRECTION}: even the ground truth cannot reach {', '.join(atoms)}"
        if self.rest_solvable is not None and any(b.stage != "tower" for b in self.blocking):
            rest = "solvable" if self.rest_solvable else "not solvable either"
            head += f" (the rest of the goal is {rest})"
        return head

    @property
    def message(self) -> str:
        if not self.found:
            if not self.blocking:
                return NO_CORRECTION
            first: dict[tuple[str, str, str], str] = {}  # one reason per object and stage
            for b in self.blocking:
                first.setdefault((b.atom, b.object, b.stage), b.text)
            return "; ".join([self.headline, *first.values()])
        parts = []
        if self.missing:
            parts.append("missing affordance facts: " + ", ".join(map(format_fact, self.missing)))
        if self.spurious:
            parts.append("spurious facts: " + ", ".join(map(format_fact, self.spurious)))
        qualifier = "" if self.smallest else " (a minimal set; smaller ones were not ruled out)"
        return "; ".join(parts) + qualifier

    def to_json(self) -> dict[str, object]:
        return {
            "found": self.found,
            "missing": [list(f) for f in self.missing],
            "spurious": [list(f) for f in self.spurious],
            "smallest": self.smallest,
            "checks": self.checks,
            "message": self.message,
            "headline": self.headline,
            "blocking": [b.to_json() for b in self.blocking],
            "rest_solvable": self.rest_solvable,
        }


class _Checker:
    """Solvability under a fact set (a `SolvabilityOracle`), cached, with a time budget."""

    def __init__(self, oracle: SolvabilityOracle, budget_s: float):
        self.oracle = oracle
        self.deadline = time.perf_counter() + budget_s
        self.cache: dict[frozenset[Fact], bool] = {}

    @property
    def expired(self) -> bool:
        return time.perf_counter() > self.deadline

    def __call__(self, facts: frozenset[Fact]) -> bool:
        if facts not in self.cache:
            self.cache[facts] = self.oracle(facts)
        return self.cache[facts]


def _apply(facts: frozenset[Fact], changes: Iterable[Change]) -> frozenset[Fact]:
    out = set(facts)
    for sign, f in changes:
        (out.add if sign == "+" else out.discard)(f)
    return frozenset(out)


def explain_unsolvable(
    scene: Scene,
    detected: Iterable[Fact],
    *,
    ground_truth: Iterable[Fact] | None = None,
    max_size: int = 2,
    timeout: float = 5.0,
    budget_s: float = 20.0,
    domain: str = "utamp2",
) -> Explanation:
    """A smallest set of corrections (missing and spurious facts) making `scene` solvable.

    `max_size` bounds the corrections tried beyond the required ones; `timeout` is per
    planner call and `budget_s` bounds the whole search. `domain`: the one planned in
    (``utamp2x``: its ground truth has the extended grasps, and the rules that refuse are
    the extended domain's).
    """
    start = time.perf_counter()
    det = frozenset(detected)
    gt = frozenset(ground_truth) if ground_truth is not None else ground_truth_for(scene, domain)
    changes: list[Change] = [("+", f) for f in sorted(gt - det)]
    changes += [("-", f) for f in sorted(det - gt) if f[0] in NEGATIVELY_USED]
    oracle = SolvabilityOracle(scene, det | gt, timeout=timeout, domain=domain)
    check = _Checker(oracle, budget_s)

    def result(
        found: bool,
        chosen: Sequence[Change],
        smallest: bool,
        blocks: tuple[Block, ...] = (),
        rest: bool | None = None,
    ) -> Explanation:
        return Explanation(
            scene=scene.name,
            found=found,
            missing=tuple(f for s, f in chosen if s == "+"),
            spurious=tuple(f for s, f in chosen if s == "-"),
            smallest=smallest,
            checks=len(check.cache) + extra_checks,
            elapsed_s=time.perf_counter() - start,
            blocking=blocks,
            rest_solvable=rest,
        )

    extra_checks = 0
    if not changes or not check(_apply(det, changes)):
        if check(gt):  # solvable under the ground truth: nothing blocks it (a time-out)
            return result(False, (), False)
        before = check.oracle.checks
        blocks, rest = blocking_goals(scene, gt, check.oracle)
        extra_checks = check.oracle.checks - before
        return result(False, (), False, blocks, rest)
    # Adding positive facts only enables actions: a correction whose omission from the full
    # set leaves the task unsolvable is in every solution (exact without removals).
    required: list[Change] = []
    if all(sign == "+" for sign, _ in changes):
        required = [c for c in changes if not check(_apply(det, [k for k in changes if k != c]))]
    optional = [c for c in changes if c not in required]
    for extra in range(0, min(max_size, len(optional)) + 1):
        for combo in itertools.combinations(optional, extra):
            if check.expired:
                break
            chosen = sorted([*required, *combo])
            if check(_apply(det, chosen)):
                return result(True, chosen, True)
        if check.expired:
            break
    kept = list(changes)
    for c in changes:  # budget exhausted: greedy deletion gives a minimal set
        if c not in required and check(_apply(det, [k for k in kept if k != c])):
            kept.remove(c)
    return result(True, kept, False)


def explain_scene(
    scene: Scene,
    method: str,
    *,
    seed: int = 0,
    noise: float = DEFAULT_NOISE,
    max_size: int = 2,
    timeout: float = 5.0,
    budget_s: float = 20.0,
) -> Explanation | None:
    """Explain `method`'s detected affordances for `scene` (None for U-TAMP-1: no affordances;
    in the method's domain, `explain_unsolvable`).

    The facts are drawn exactly as `plan_scene(scene, method, seed=seed, noise=noise)` draws
    them, so this explains that call's outcome.
    """
    spec = method_spec(method)
    if spec.domain not in EXPLAINED_DOMAINS:
        return None
    rng = detection_rng(seed, scene.name)
    facts, _ = affordances_for(scene, spec.affordances, rng, noise, spec.domain)
    return explain_unsolvable(
        scene,
        facts,
        max_size=max_size,
        timeout=timeout,
        budget_s=budget_s,
        domain=spec.domain,
    )
