"""The `utamp` command line: scenes, plan, validate (run, eval and train join as they land).

Exit codes: 0 success (also for `plan` when the scene is unsolvable: see `solved`),
1 an invalid plan (`validate`), 2 bad input (unknown scene, malformed file, ...).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from utamp_gym.errors import UtampError


def _cmd_scenes(args: argparse.Namespace) -> int:
    from utamp_gym.scene.io import scene_to_toml
    from utamp_gym.suites import SUITES, resolve_scene, suite_scenes

    if args.scenes_cmd == "list":
        for suite in (args.suite,) if args.suite else SUITES:
            for scene in suite_scenes(suite):
                print(scene.name)
        return 0
    sys.stdout.write(scene_to_toml(resolve_scene(args.name)))
    return 0


def _cmd_plan(args: argparse.Namespace) -> int:
    from utamp_gym.planning.methods import plan_scene
    from utamp_gym.suites import resolve_scene

    scene = resolve_scene(args.scene)
    outcome = plan_scene(
        scene,
        args.method,
        seed=args.seed,
        timeout=args.timeout,
        search=args.search,
        noise=args.noise,
    )
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "domain.pddl").write_text(outcome.domain)
        (out / "problem.pddl").write_text(outcome.problem)
        (out / "plan.txt").write_text("".join(f"{a}\n" for a in outcome.plan))
    if args.json:
        print(json.dumps(outcome.to_json(), indent=2))
    elif outcome.solved:
        print(
            f"{scene.name} [{args.method}]: {outcome.plan_length} steps, "
            f"{outcome.planning_time_s * 1000:.1f} ms"
        )
        for step in outcome.plan:
            print(f"  {step}")
    else:
        print(f"{scene.name} [{args.method}]: not solved: {outcome.reason}")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from utamp_gym.symbolic.validate import validate_files

    result = validate_files(args.domain, args.problem, args.plan)
    if result.valid:
        print(f"valid: {result.steps_applied} steps reach the goal")
        return 0
    print(result.message, file=sys.stderr)
    return 1


def build_parser() -> argparse.ArgumentParser:
    from utamp_gym.planning.fast_downward import SEARCH_CONFIGS
    from utamp_gym.planning.methods import DEFAULT_NOISE, METHODS
    from utamp_gym.suites import SUITES

    parser = argparse.ArgumentParser(prog="utamp", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)

    scenes = sub.add_parser("scenes", help="list or show benchmark scenes")
    ssub = scenes.add_subparsers(dest="scenes_cmd", required=True)
    lst = ssub.add_parser("list", help="scene names, one per line")
    lst.add_argument("--suite", choices=SUITES)
    show = ssub.add_parser("show", help="a scene as TOML (usable as a scene file)")
    show.add_argument("name")
    scenes.set_defaults(func=_cmd_scenes)

    plan = sub.add_parser("plan", help="plan a scene with Fast Downward")
    plan.add_argument(
        "scene", help="suite scene (pick-place/017), packaged scene or scene-file path"
    )
    plan.add_argument("--method", choices=METHODS, default="utamp2-gt")
    plan.add_argument("--seed", type=int, default=0)
    plan.add_argument("--timeout", type=float, default=30.0, help="planner time limit (s)")
    plan.add_argument("--search", choices=SEARCH_CONFIGS, default="lama-first")
    plan.add_argument(
        "--noise", type=float, default=DEFAULT_NOISE, help="attribute noise for utamp2-noisy"
    )
    plan.add_argument("--json", action="store_true", help="print one JSON object")
    plan.add_argument("--out", help="write domain.pddl, problem.pddl and plan.txt here")
    plan.set_defaults(func=_cmd_plan)

    val = sub.add_parser("validate", help="check a plan against a domain and problem")
    val.add_argument("domain")
    val.add_argument("problem")
    val.add_argument("plan")
    val.set_defaults(func=_cmd_validate)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except UtampError as exc:
        print(f"utamp: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `utamp scenes list | head`
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
