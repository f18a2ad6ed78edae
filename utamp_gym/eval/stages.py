"""Stage-wise scoring: where the pipeline image -> attributes -> affordances -> plan ->
physics lost an episode, and the per-attribute accuracy columns of the eval rows.

A failed run is charged to the first stage that went wrong (`failure_stage`):

* ``perception`` — the affordances differ from the ground truth (F1 < 1) *and* the plan
  was lost because of it (no plan, or a plan the ground truth forbids), for a method whose
  attributes are detected (``utamp2-noisy``, ``utamp2-perceived``, the VLM methods);
* ``affordances`` — the same, for a method whose affordances are not detected from
  attributes it perceives (``utamp2-rules``: the rules themselves were wrong);
* ``plan`` — no valid plan although the affordances were right (F1 = 1 or no affordances,
  e.g. U-TAMP-1's invalid plans, a planner time-out);
* ``physics`` — a plan valid under the ground truth failed in execution;
* ``crash`` — the run raised.
"""

from __future__ import annotations

from utamp_gym.methods.attributes import ATTRIBUTES

ATTRIBUTE_COLUMNS = tuple(f"acc_{a}" for a in ATTRIBUTES)
STAGES = ("perception", "affordances", "plan", "physics", "crash")
DETECTED = ("utamp2-noisy", "utamp2-perceived", "utamp2-vlm", "vlm-planner")


def failure_stage(
    method: str,
    *,
    success: bool,
    crashed: bool,
    solved: bool,
    valid_gt: bool | None,
    affordance_f1: float | None,
    grounding: str,
) -> str:
    """The stage that lost a run (module docstring), ``""`` for a success."""
    if success:
        return ""
    if crashed:
        return "crash"
    plan_ok = solved and valid_gt is not False
    if plan_ok and grounding == "physics":
        return "physics"
    if affordance_f1 is not None and affordance_f1 < 1.0 - 1e-9:
        detected = method in DETECTED or method.partition(":")[0] == "utamp2-perceived"
        return "perception" if detected else "affordances"
    return "plan"


__all__ = ["ATTRIBUTES", "ATTRIBUTE_COLUMNS", "DETECTED", "STAGES", "failure_stage"]
