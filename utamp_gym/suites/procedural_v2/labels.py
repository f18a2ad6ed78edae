"""Achievability labels of procedural-v2 goals: the planner's verdict, checked against Fast
Downward's own translator.

`label` plans the scene's goal with `spec.LABEL_METHOD` (our grounder and SAS writer, then
Fast Downward's search) under the split file's domain; `fd_agrees` plans the same PDDL
problem with Fast Downward's Python translator instead of ours (`planning.fast_downward.solve`,
``translator="fd"``) and asks whether it reaches the same verdict. A seed is kept only when
both agree and neither timed out (`selection`).
"""

from __future__ import annotations

from typing import NamedTuple

from utamp_gym.errors import PlanningTimeout
from utamp_gym.planning.fast_downward import solve
from utamp_gym.planning.methods import affordances_for, method_spec, plan_scene
from utamp_gym.scene.model import Scene
from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD, LABEL_TIMEOUT
from utamp_gym.symbolic.problem import build_problem, domain_text


class Label(NamedTuple):
    achievable: bool
    plan_length: int  # actions; 0 when unachievable
    timed_out: bool
    planning_time_s: float


def label(scene: Scene, timeout: float = LABEL_TIMEOUT) -> Label:
    """The planner's verdict on the scene's goal (`scene.goal`, else the paper's tower)."""
    out = plan_scene(scene, LABEL_METHOD, timeout=timeout)
    return Label(out.solved, out.plan_length, out.timed_out, out.planning_time_s)


def fd_agrees(scene: Scene, achievable: bool, timeout: float = LABEL_TIMEOUT) -> bool | None:
    """Whether Fast Downward's translator reaches the same verdict (None: it timed out)."""
    spec = method_spec(LABEL_METHOD)
    facts, _ = affordances_for(scene, spec.affordances, None, 0.0, spec.domain)
    problem = build_problem(scene, facts, spec.domain)
    try:
        result = solve(domain_text(spec.domain), problem.text, translator="fd", timeout=timeout)
    except PlanningTimeout:
        return None
    return result.solved == achievable


__all__ = ["Label", "fd_agrees", "label"]
