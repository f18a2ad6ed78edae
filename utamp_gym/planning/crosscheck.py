"""Check any plan against the U-TAMP-2 ground truth (or an extended domain's, e.g. ``utamp2x``).

U-TAMP-1 actions have the same parameters as U-TAMP-2's, so a U-TAMP-1 plan can be
replayed in the U-TAMP-2 domain with the ground-truth affordances: the first action
whose affordance preconditions fail (``canLift``, ``isP2PSupportive``, ...) is where
the plan violates physics, and where it is expected to fail when executed.
"""

from __future__ import annotations

from collections.abc import Sequence

from utamp_gym.affordances.sources import EXTENDED_DOMAINS, ground_truth_for
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.pddl import Domain, Problem, parse_domain, parse_plan, parse_problem
from utamp_gym.symbolic.problem import build_problem, domain_text
from utamp_gym.symbolic.validate import ValidationResult, holds, validate_plan


def checking_domain(domain: str) -> str:
    """The domain a plan of `domain` is checked (and played) in: an extended domain's own,
    else U-TAMP-2 (U-TAMP-1's actions are U-TAMP-2's without the affordance preconditions)."""
    return domain if domain in EXTENDED_DOMAINS else "utamp2"


def _ground_truth_task(scene: Scene, domain: str = "utamp2") -> tuple[Domain, Problem]:
    name = checking_domain(domain)
    parsed = parse_domain(domain_text(name), source=f"{name}.pddl")
    problem = parse_problem(
        build_problem(scene, ground_truth_for(scene, name), name).text,
        source=f"{scene.name} (ground truth)",
    )
    return parsed, problem


def affordance_violations(
    scene: Scene, plan: Sequence[str], domain: str = "utamp2"
) -> list[tuple[int, str]]:
    """Every step (0-based) whose static U-TAMP-2 preconditions are false under the ground
    truth, with the first such literal: the affordances each action ignores.

    Unlike `check_against_ground_truth`, which stops at the first failure, this looks at
    every step (static facts do not depend on the state reached), so a physical failure
    can be matched to the violation it stems from. Steps not in the domain are skipped.
    """
    parsed, problem = _ground_truth_task(scene, domain)
    fluent = parsed.fluent_predicates()
    init = frozenset(problem.init)
    out = []
    for i, step in enumerate(parse_plan("\n".join(plan))):
        action = parsed.actions.get(step[0])
        if action is None or action.arity != len(step) - 1:
            continue
        pre = action.instantiate(step[1:])[0]
        bad = next(
            (lit for lit in pre if lit.atom.predicate not in fluent and not holds(lit, init)),
            None,
        )
        if bad is not None:
            out.append((i, parsed.show(bad)))
    return out


def check_against_ground_truth(
    scene: Scene, plan: Sequence[str], domain: str = "utamp2"
) -> ValidationResult:
    """Replay `plan` in U-TAMP-2 (or the extended `domain` it was planned in,
    `checking_domain`) with the scene's ground-truth affordances."""
    parsed, problem = _ground_truth_task(scene, domain)
    return validate_plan(parsed, problem, parse_plan("\n".join(plan)))
