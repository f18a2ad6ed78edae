"""`utamp plan`: plan a scene with Fast Downward (imports neither Gymnasium nor the physics
stack)."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING, Any

from utamp_gym.affordances.sources import DEFAULT_NOISE
from utamp_gym.cli import help_line
from utamp_gym.cli.common import METHOD_HELP, SCENE_HELP, default_method, timeout_seconds
from utamp_gym.deadline import Deadline
from utamp_gym.outputs import output_dir
from utamp_gym.planning.downward import DEFAULT_SEARCH, SEARCH_CONFIGS
from utamp_gym.planning.methods import METHODS, method_spec, plan_scene
from utamp_gym.suites import resolve_scene

if TYPE_CHECKING:
    from utamp_gym.planning.methods import PlanOutcome
    from utamp_gym.scene.model import Scene


def _cmd_plan(args: argparse.Namespace) -> int:
    # Bounds the whole command: counted from `main`'s start (argument parsing and the
    # planner's imports included), not from when planning begins.
    deadline = Deadline.after(args.timeout, args.started)
    scene = resolve_scene(args.scene)
    args.method = args.method or default_method(scene.name)
    out = None if args.out is None else output_dir(args.out, "--out")
    doubt = ""  # how the perceived attributes in doubt were planned (`DoubtfulPlan.note`)
    if args.method == "utamp2-perceived":  # looks at the scene first (renders it)
        # lazy: keeps `utamp --help` from loading utamp_gym.methods.perceived
        from utamp_gym.methods.perceived import plan_perceived

        outcome, seen = plan_perceived(scene, args.seed, search=args.search, deadline=deadline)
        doubt = "" if seen is None else seen.doubt.note()
    else:
        outcome = plan_scene(
            scene,
            args.method,
            seed=args.seed,
            search=args.search,
            noise=args.noise,
            deadline=deadline,
        )
    if out is not None:  # names other planners accept (`utamp_gym.symbolic.export`)
        # lazy: keeps `utamp --help` from loading utamp_gym.symbolic.export
        from utamp_gym.symbolic.export import export_task

        task = export_task(outcome.domain, outcome.problem, outcome.plan, scene.name)
        (out / "domain.pddl").write_text(task.domain)
        (out / "problem.pddl").write_text(task.problem)
        (out / "plan.txt").write_text("".join(f"{a}\n" for a in task.plan))
    explanation = _explain(scene, outcome) if args.explain and not outcome.solved else None
    if args.json:
        data = outcome.to_json()
        if doubt:
            data["doubt"] = doubt
        if args.explain:
            data["explanation"] = explanation
        print(json.dumps(data, indent=2))
    elif outcome.timed_out:
        print(f"{scene.name} [{args.method}]: timed out during {outcome.phase}: {outcome.reason}")
    elif outcome.solved:
        print(
            f"{scene.name} [{args.method}]: {outcome.plan_length} steps, "
            f"{outcome.planning_time_s * 1000:.1f} ms"
        )
        if doubt:
            print(f"  ({doubt})")
        for step in outcome.plan:
            print(f"  {step}")
    else:
        print(f"{scene.name} [{args.method}]: not solved: {outcome.reason}")
        if explanation is not None:
            _print_explanation(explanation)
    return 0


def _print_explanation(explanation: dict[str, Any]) -> None:
    """``why not:`` and, when the ground truth itself blocks the goal, each blocked goal atom
    with one line a reason."""
    blocks = explanation.get("blocking") or []
    if not blocks:
        print(f"  why not: {explanation['message']}")
        return
    print(f"  why not: {explanation['headline']}:")
    for atom in dict.fromkeys(b["atom"] for b in blocks):
        print(f"    {atom}:")
        for b in blocks:
            if b["atom"] == atom:
                print(f"      {b['subject']}: {b['detail']} [{b['rule']}]")


def _explain(scene: Scene, outcome: PlanOutcome) -> dict[str, Any]:
    """Why-not explanation of an unsolved outcome (methods with affordances: U-TAMP-2 and its
    extended domain, explained in the method's own)."""
    # lazy: keeps `utamp --help` from loading utamp_gym.eval.explain
    from utamp_gym.eval.explain import EXPLAINED_DOMAINS, explain_unsolvable

    domain = method_spec(outcome.method).domain
    if domain not in EXPLAINED_DOMAINS:
        return {"found": False, "message": "explanations need affordances (utamp1 has none)"}
    return explain_unsolvable(scene, outcome.facts, domain=domain).to_json()


def add_parser(sub: Any) -> None:
    """``utamp plan SCENE``."""
    plan = sub.add_parser("plan", help=help_line("plan"))
    plan.add_argument("scene", help=SCENE_HELP)
    plan.add_argument("--method", choices=METHODS, help=METHOD_HELP)
    plan.add_argument("--seed", type=int, default=0, help="seed of utamp2-noisy's detection")
    plan.add_argument(
        "--timeout",
        type=timeout_seconds,
        default=30.0,
        help="time limit of the whole command (s, at most one day)",
    )
    plan.add_argument(
        "--search",
        choices=SEARCH_CONFIGS,
        default=DEFAULT_SEARCH,
        help="Fast Downward search (astar-*: optimal plans)",
    )
    plan.add_argument(
        "--noise", type=float, default=DEFAULT_NOISE, help="attribute noise for utamp2-noisy"
    )
    plan.add_argument("--json", action="store_true", help="print one JSON object")
    plan.add_argument(
        "--out",
        help="write domain.pddl, problem.pddl and plan.txt here (an object named like a domain "
        "symbol is renamed, e.g. base -> base-obj, as a comment in problem.pddl records)",
    )
    plan.add_argument(
        "--explain",
        action="store_true",
        help=(
            "if unsolved, name the missing affordance facts that block the scene, or, when "
            "even the ground truth blocks it, the goal atoms and the rules that refuse them"
        ),
    )
    plan.set_defaults(func=_cmd_plan)
