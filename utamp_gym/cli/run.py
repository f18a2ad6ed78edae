"""`utamp run`: plan a scene, then execute the plan in MuJoCo physics (open or closed loop)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from utamp_gym.cli import help_line
from utamp_gym.cli.common import METHOD_HELP, SCENE_HELP, add_physics_options, default_method
from utamp_gym.errors import UtampError
from utamp_gym.outputs import output_file
from utamp_gym.planning.methods import METHODS
from utamp_gym.suites import resolve_scene
from utamp_gym.tasks.language import instruction


def _cmd_run(args: argparse.Namespace) -> int:
    # lazy: keeps `utamp --help` from loading utamp_gym.agents.runs
    from utamp_gym.agents.runs import run_episode

    args.method = args.method or default_method(resolve_scene(args.scene).name)
    if args.closed_loop:
        return _run_closed_loop(args)
    if args.video:
        output_file(args.video, "--video")
    physics = {
        "seed": args.seed,
        "video": args.video,
        "pose_noise": args.pose_noise,
        "disturbance": args.disturbance,
        "perception": args.perception,
    }
    scene = resolve_scene(args.scene)
    if args.method == "utamp2-perceived":  # looks at the scene first (renders it)
        # lazy: keeps `utamp --help` from loading utamp_gym.methods.perceived
        from utamp_gym.methods.perceived import run_perceived_episode

        result = run_perceived_episode(scene, **physics)
    else:
        result = run_episode(args.scene, args.method, **physics)
    data = result.to_dict()
    if args.json:
        data.pop("steps", None)
        print(json.dumps(data, indent=2))
        return 0
    status = "success" if result.success else f"failure: {result.failure}"
    print(f"{result.scene} [{result.method}, seed {result.seed}]: {status}")
    print(
        f"  plan {len(result.plan)} steps, planning {result.planning_time_s:.3f} s, "
        f"execution {result.execution_time_s:.2f} s, wall {result.wall_time_s:.2f} s"
    )
    if scene.goal is not None and scene.goal.template != "tower":  # the scene's own goal
        print(f"  goal ({scene.goal.template}): {instruction(scene, scene.goal)}")
        return 0
    base = scene.tower_base  # the tray, or a procedural scene's base (a tray or a board)
    print(
        f"  tower on {base} ({scene.type_of(base).name}): "
        f"{' / '.join(result.final_stack) or '(empty)'}"
    )
    return 0


def _run_closed_loop(args: argparse.Namespace) -> int:
    from dataclasses import asdict

    # lazy: keeps `utamp --help` from loading utamp_gym.eval.closed_loop
    from utamp_gym.eval.closed_loop import run_closed_loop

    if args.video:
        raise UtampError("--video records open-loop runs only (drop --closed-loop)")
    name = resolve_scene(args.scene).name
    result = run_closed_loop(
        args.scene,
        args.method,
        seed=args.seed,
        disturbance=args.disturbance,
        pose_noise=args.pose_noise,
        perception=args.perception,
    )
    if args.json:
        print(json.dumps({"scene": name, "method": args.method, **asdict(result)}, indent=2))
        return 0
    status = "success" if result.success else f"failure: {result.failure}"
    print(f"{name} [{args.method}, seed {args.seed}, closed loop]: {status}")
    print(
        f"  {len(result.actions)} actions, {result.n_replans} replans, {result.n_faults} faults,"
        f" planning {result.planning_time_s:.3f} s, execution {result.execution_time_s:.2f} s"
    )
    return 0


def add_parser(sub: Any) -> None:
    """``utamp run SCENE``."""
    run = sub.add_parser("run", help=help_line("run"))
    run.add_argument("scene", help=SCENE_HELP)
    run.add_argument("--method", choices=METHODS, help=METHOD_HELP)
    run.add_argument("--seed", type=int, default=0, help="pose noise, IK restarts and OMPL seed")
    run.add_argument("--video", help="write an MP4 (or .gif) of the episode here")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    add_physics_options(run)
    run.add_argument(
        "--closed-loop",
        action="store_true",
        help="act with the planner policy in the env, replanning from the perceived state",
    )
    run.set_defaults(func=_cmd_run)
