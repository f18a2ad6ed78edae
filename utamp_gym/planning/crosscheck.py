"""Check any plan against the U-TAMP-2 ground truth.

U-TAMP-1 actions have the same parameters as U-TAMP-2's, so a U-TAMP-1 plan can be
replayed in the U-TAMP-2 domain with the ground-truth affordances: the first action
whose affordance preconditions fail (``canLift``, ``isP2PSupportive``, ...) is where
the plan violates physics, and where it is expected to fail when executed.
"""

from __future__ import annotations

from collections.abc import Sequence

from utamp_gym.planning.methods import ground_truth_for
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.pddl import parse_domain, parse_plan, parse_problem
from utamp_gym.symbolic.problem import build_problem, domain_text
from utamp_gym.symbolic.validate import ValidationResult, validate_plan


def check_against_ground_truth(scene: Scene, plan: Sequence[str]) -> ValidationResult:
    """Replay `plan` in U-TAMP-2 with the scene's ground-truth affordances."""
    domain = parse_domain(domain_text("utamp2"), source="utamp2.pddl")
    problem = parse_problem(
        build_problem(scene, ground_truth_for(scene), "utamp2").text,
        source=f"{scene.name} (ground truth)",
    )
    return validate_plan(domain, problem, parse_plan("\n".join(plan)))
