"""The `utamp` command line: scenes, plan, validate, run, view, eval, train, demos.

Exit codes: 0 success (also for `plan` when the scene is unsolvable or the planner timed out:
see `solved` and `timed_out`), 1 an invalid plan (`validate`) or an `eval` sweep with crashed
runs (named on stderr; their rows are in results.csv and run again on resume), 2 bad input
(unknown scene, malformed file, bad option value, a failed training seed, ...), 130
interrupted (Ctrl-C).

Each subcommand imports what it needs when it runs; `utamp plan` imports neither Gymnasium
nor the physics stack (the RL parser and the env registration load only for the
subcommands that use them).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from utamp_gym.errors import UtampError
from utamp_gym.outputs import output_dir, output_file

if TYPE_CHECKING:
    from utamp_gym.planning.methods import PlanOutcome
    from utamp_gym.scene.model import Scene


def _cmd_scenes(args: argparse.Namespace) -> int:
    from utamp_gym.scene.io import scene_to_toml
    from utamp_gym.suites import (
        ALL_SUITES,
        all_scene_names,
        packaged_scene_names,
        resolve_scene,
        scene_summary,
    )

    if args.scenes_cmd == "list":
        if not args.suite and not args.json:  # packaged scenes (kitchen-demo), then suites
            for name in packaged_scene_names():
                print(name)
        for suite in (args.suite,) if args.suite else ALL_SUITES:
            if args.json:  # one JSON object per line and scene
                for record in scene_summary(suite):
                    print(json.dumps(record))
            else:
                for name in all_scene_names(suite):
                    print(name)
        return 0
    sys.stdout.write(scene_to_toml(resolve_scene(args.name)))
    return 0


def _cmd_plan(args: argparse.Namespace) -> int:
    from utamp_gym.deadline import Deadline
    from utamp_gym.planning.methods import plan_scene
    from utamp_gym.suites import resolve_scene

    # Bounds the whole command: counted from `main`'s start (argument parsing and the
    # planner's imports included), not from when planning begins.
    deadline = Deadline.after(args.timeout, args.started)
    scene = resolve_scene(args.scene)
    out = None if args.out is None else output_dir(args.out, "--out")
    if args.method == "utamp2-perceived":  # looks at the scene first (renders it)
        from utamp_gym.eval.perceived import plan_perceived

        outcome = plan_perceived(scene, args.seed, search=args.search, deadline=deadline)[0]
    else:
        outcome = plan_scene(
            scene,
            args.method,
            seed=args.seed,
            search=args.search,
            noise=args.noise,
            deadline=deadline,
        )
    if out is not None:
        (out / "domain.pddl").write_text(outcome.domain)
        (out / "problem.pddl").write_text(outcome.problem)
        (out / "plan.txt").write_text("".join(f"{a}\n" for a in outcome.plan))
    explanation = _explain(scene, outcome) if args.explain and not outcome.solved else None
    if args.json:
        data = outcome.to_json()
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
        for step in outcome.plan:
            print(f"  {step}")
    else:
        print(f"{scene.name} [{args.method}]: not solved: {outcome.reason}")
        if explanation is not None:
            print(f"  why not: {explanation['message']}")
    return 0


def _explain(scene: Scene, outcome: PlanOutcome) -> dict[str, Any]:
    """Why-not explanation of an unsolved outcome (U-TAMP-2 methods only)."""
    from utamp_gym.eval.explain import explain_unsolvable
    from utamp_gym.planning.methods import method_spec

    if method_spec(outcome.method).domain != "utamp2":
        return {"found": False, "message": "explanations need U-TAMP-2 affordances (not utamp1)"}
    return explain_unsolvable(scene, outcome.facts).to_json()


def _cmd_eval(args: argparse.Namespace) -> int:
    if args.eval_cmd == "merge":
        return _cmd_eval_merge(args)
    missing = [flag for flag, value in (("--suite", args.suite), ("--out", args.out)) if not value]
    if missing:
        args.eval_parser.error(f"the following arguments are required: {', '.join(missing)}")
    from utamp_gym.distributed import make_executor
    from utamp_gym.eval.summary import to_markdown
    from utamp_gym.eval.sweep import SweepConfig, parse_shard, run_sweep, write_outputs

    noise = (args.noise,)
    if args.sweep_noise:
        try:
            noise = tuple(float(p) for p in args.sweep_noise.split(",") if p.strip())
        except ValueError:
            raise UtampError(
                f"--sweep-noise: expected numbers like 0,0.01,0.05, got {args.sweep_noise!r}"
            ) from None
    default = "utamp2-noisy" if args.sweep_noise else "utamp1,utamp2-gt,utamp2-rules,utamp2-noisy"
    methods = tuple(m.strip() for m in (args.methods or default).split(",") if m.strip())
    cfg = SweepConfig(
        suite=args.suite,
        methods=methods,
        seeds=args.seeds,
        grounding=args.grounding,
        limit=args.limit,
        noise=noise,
        timeout=args.timeout,
        explain=not args.no_explain,
        closed_loop=args.closed_loop,
        disturbance=args.disturbance,
        pose_noise=args.pose_noise,
        perception=args.perception,
        seed_offset=args.seed_offset,
        scenes=args.scenes,
        shard=None if args.shard is None else parse_shard(args.shard),
    )
    output_dir(args.out, "--out")
    executor = make_executor(args.executor, workers=args.workers, ray_address=args.ray_address)
    try:
        report = run_sweep(cfg, args.out, progress=not args.quiet, executor=executor)
    except KeyboardInterrupt:
        print(
            f"utamp eval: interrupted; finished runs are in {Path(args.out) / 'results.csv'}: "
            "run the same command (with either executor) to resume",
            file=sys.stderr,
        )
        return 130
    summary = write_outputs(report)
    if not args.quiet:
        sys.stdout.write(to_markdown(summary))
    print(
        f"{report.ran} run(s), {report.resumed} resumed from {Path(args.out) / 'results.csv'}; "
        f"{report.wall_time_s:.1f} s; wrote results.csv, summary.md, summary.json and figures "
        f"in {args.out}"
    )
    return _report_crashes(report.crashed, len(report.rows))


def _report_crashes(crashed: Sequence[Any], total: int) -> int:
    """Exit code 1 and a note on stderr when runs crashed (0 otherwise): a crash is not an
    outcome of the method, so a sweep with crashes is incomplete."""
    if not crashed:
        return 0
    reasons: dict[str, int] = {}
    for row in crashed:
        reasons[row.failure_reason] = reasons.get(row.failure_reason, 0) + 1
    top = sorted(reasons.items(), key=lambda kv: -kv[1])[:3]
    shown = "; ".join(f"{n}x {reason}" for reason, n in top)
    print(
        f"utamp eval: {len(crashed)} of {total} run(s) crashed ({shown}); their rows say "
        "crashed=true, and they run again when the same command resumes",
        file=sys.stderr,
    )
    return 1


def _cmd_eval_merge(args: argparse.Namespace) -> int:
    from utamp_gym.eval.merge import merge_outputs
    from utamp_gym.eval.summary import to_markdown

    output_dir(args.merge_out, "OUT")
    summary = merge_outputs(args.merge_out, args.dirs)
    if not args.quiet:
        sys.stdout.write(to_markdown(summary))
    print(
        f"merged {summary['runs']} run(s) from {len(summary['merged_from'])} folder(s) "
        f"({summary['duplicate_rows']} duplicate(s) dropped); wrote results.csv, summary.md, "
        f"summary.json and figures in {args.merge_out}"
    )
    return 0


def _add_eval_parser(sub: Any) -> None:
    """``utamp eval --suite ... --out DIR`` (a sweep) and ``utamp eval merge OUT DIR...``.

    argparse has no optional sub-command next to required options, so ``merge`` is an
    optional sub-command and the sweep's required options are checked in `_cmd_eval`.
    """
    from utamp_gym.distributed import EXECUTORS
    from utamp_gym.planning.methods import DEFAULT_NOISE
    from utamp_gym.suites import ALL_SUITES as SUITES

    ev = sub.add_parser(
        "eval",
        help=EVAL_HELP,
        usage="utamp eval --suite SUITE --out DIR [options]\n       utamp eval merge OUT DIR...",
    )
    ev.add_argument("--suite", choices=SUITES, help="required for a sweep")
    ev.add_argument(
        "--methods",
        help="comma-separated: utamp1, utamp2-gt, utamp2-rules, utamp2-noisy, utamp2-vlm, "
        "vlm-planner, rl:PATH (a model.zip from `utamp train`; its env options come from the "
        "model) (default: the first four; utamp2-noisy alone with --sweep-noise)",
    )
    ev.add_argument("--seeds", type=int, default=1, help="K seeds per scene and method")
    ev.add_argument(
        "--seed-offset", type=int, default=0, help="the first seed: seeds S..S+K-1 (default 0)"
    )
    ev.add_argument(
        "--scenes", metavar="PATTERN", help="only scenes matching this glob (pick-place/0*)"
    )
    ev.add_argument(
        "--shard", metavar="I/N", help="only the I-th of N parts of the runs (by a stable hash)"
    )
    ev.add_argument(
        "--workers",
        type=int,
        help="worker processes (default: CPU count; 0: in this process); with --executor ray "
        "the CPUs of a new local Ray instance",
    )
    ev.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="local",
        help="local worker processes, or Ray tasks (the utamp-gym[ray] extra)",
    )
    ev.add_argument(
        "--ray-address",
        metavar="ADDR",
        help="Ray cluster to use (default: $RAY_ADDRESS, else a new local Ray instance)",
    )
    ev.add_argument(
        "--grounding",
        choices=("physics", "symbolic"),
        default="physics",
        help="execute plans in MuJoCo, or check them against the ground-truth model",
    )
    ev.add_argument("--limit", type=int, help="only the first N (matching) scenes of the suite")
    ev.add_argument(
        "--noise", type=float, default=DEFAULT_NOISE, help="attribute noise for utamp2-noisy"
    )
    ev.add_argument(
        "--sweep-noise", help="comma-separated noise levels for utamp2-noisy (success vs F1)"
    )
    ev.add_argument("--timeout", type=timeout_seconds, default=30.0, help="planner time limit (s)")
    ev.add_argument(
        "--no-explain", action="store_true", help="do not explain unsolved U-TAMP-2 runs"
    )
    _add_physics_options(ev)
    ev.add_argument(
        "--closed-loop",
        action="store_true",
        help="run the planner policy in the env (perceive, replan; at most "
        "utamp_gym.eval.closed_loop.MAX_STEPS macro actions) instead of plan-then-execute",
    )
    ev.add_argument("--quiet", action="store_true", help="no progress bar, no table")
    ev.add_argument("--out", help="output directory (re-use it to resume); required for a sweep")
    ev.set_defaults(func=_cmd_eval, eval_parser=ev, eval_cmd=None)
    esub = ev.add_subparsers(dest="eval_cmd", metavar="merge")
    merge = esub.add_parser(
        "merge",
        prog="utamp eval merge",
        help="merge output folders (shards, seed ranges) into OUT and rewrite its summaries",
        description="Merge the results.csv of several `utamp eval` output folders into OUT "
        "(each run once; a run with different outcomes in two folders is an error) and write "
        "summary.md, summary.json and the figures there.",
    )
    merge.add_argument("merge_out", metavar="OUT", help="output folder (may be one of DIR)")
    merge.add_argument("dirs", metavar="DIR", nargs="+", help="`utamp eval` output folders")
    merge.add_argument("--quiet", action="store_true", help="do not print the table")


def _cmd_run(args: argparse.Namespace) -> int:
    from utamp_gym.sim.execute import run_episode
    from utamp_gym.suites import resolve_scene

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
        from utamp_gym.eval.perceived import run_perceived_episode

        result = run_perceived_episode(scene, **physics)
    else:
        result = run_episode(scene, args.method, **physics)
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
    print(f"  tower on the tray: {' / '.join(result.final_stack) or '(empty)'}")
    return 0


def _run_closed_loop(args: argparse.Namespace) -> int:
    from dataclasses import asdict

    from utamp_gym.eval.closed_loop import run_closed_loop
    from utamp_gym.suites import resolve_scene

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


def _cmd_view(args: argparse.Namespace) -> int:
    """Open a scene in a window until it is closed (MuJoCo's viewer, or the schematic)."""
    from utamp_gym.env.viewer import require_display
    from utamp_gym.suites import resolve_scene

    scene = resolve_scene(args.scene)
    video = "out/" + scene.name.replace("/", "-") + ".mp4"
    require_display("utamp view", f"utamp run {args.scene} --video {video} (a video, no display)")
    if args.symbolic:
        from utamp_gym.env.viewer import show_schematic

        show_schematic(scene)
        return 0
    import mujoco.viewer
    import numpy as np

    from utamp_gym.sim.backend import MujocoBackend

    backend = MujocoBackend()
    backend.reset(scene, np.random.default_rng(args.seed))
    # MuJoCo's viewer runs the physics; the servos hold the arm at its ready pose
    mujoco.viewer.launch(backend.model, backend.data, show_left_ui=False, show_right_ui=False)
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from utamp_gym.symbolic.validate import validate_files

    result = validate_files(args.domain, args.problem, args.plan)
    if result.valid:
        print(f"valid: {result.steps_applied} steps reach the goal")
        return 0
    print(result.message, file=sys.stderr)
    return 1


MAX_TIMEOUT_S = 86400.0
"""The largest accepted ``--timeout`` (one day): anything longer is a typo."""
LIGHT_COMMANDS = ("scenes", "plan", "validate")
"""Subcommands that never build an env: the Gymnasium env ids are not registered for them."""


class _HelpFormatter(argparse.HelpFormatter):
    """argparse's help formatter at the same width (``$COLUMNS``, else the terminal's, else
    80 columns, less 2), found without importing `shutil` as argparse does: argparse builds a
    formatter for every argument it adds, and that import (~3 ms) was on `utamp plan`'s path."""

    def __init__(
        self,
        prog: str,
        indent_increment: int = 2,
        max_help_position: int = 24,
        width: int | None = None,
    ) -> None:
        if width is None:
            width = _terminal_columns() - 2
        super().__init__(prog, indent_increment, max_help_position, width)


def _terminal_columns() -> int:
    """The columns `shutil.get_terminal_size` reports (same rules, same fallback of 80)."""
    import os

    try:
        columns = int(os.environ["COLUMNS"])
    except (KeyError, ValueError):
        columns = 0
    if columns <= 0:
        try:
            columns = os.get_terminal_size(sys.__stdout__.fileno()).columns
        except (AttributeError, ValueError, OSError):
            columns = 0
    return columns or 80


class _Parser(argparse.ArgumentParser):
    """Reports a usage error as one line on stderr and exits 2; formats help with
    `_HelpFormatter` unless told otherwise."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def timeout_seconds(text: str) -> float:
    """``--timeout`` values: a positive, finite number of seconds up to `MAX_TIMEOUT_S`."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and 0 < value <= MAX_TIMEOUT_S):
        raise argparse.ArgumentTypeError(
            f"must be a positive number of seconds, at most {MAX_TIMEOUT_S:g} (one day); "
            f"got {text!r}"
        )
    return value


def _probability(text: str) -> float:
    value = _finite(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be a probability in [0, 1], got {text}")
    return value


def _pose_noise(text: str) -> float:
    from utamp_gym.backend import MAX_POSE_NOISE

    value = _finite(text)
    if not 0.0 <= value <= MAX_POSE_NOISE:
        raise argparse.ArgumentTypeError(f"must be in [0, {MAX_POSE_NOISE}] metres, got {text}")
    return value


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return value


def _add_physics_options(parser: argparse.ArgumentParser) -> None:
    """--pose-noise and --disturbance (physics execution)."""
    from utamp_gym.backend import DEFAULT_POSE_NOISE

    parser.add_argument(
        "--pose-noise",
        type=_pose_noise,
        default=DEFAULT_POSE_NOISE,
        metavar="M",
        help="std of the robot's object-position estimates in metres (yaw scales with it; "
        f"default {DEFAULT_POSE_NOISE})",
    )
    parser.add_argument(
        "--disturbance",
        type=_probability,
        default=0.0,
        metavar="P",
        help="probability of an injected fault (push, drop, wrong belief) per macro action",
    )
    parser.add_argument(
        "--perception",
        choices=("gaussian", "rgbd"),
        default="gaussian",
        help="where the robot's object poses come from: the true pose plus --pose-noise "
        "(gaussian, default) or rendered RGB-D cameras (rgbd; --pose-noise then unused)",
    )


def _help_line(command: str) -> str:
    return next(help_line for name, _, help_line in SUBCOMMANDS if name == command)


def _add_scenes_parser(sub: Any) -> None:
    from utamp_gym.suites import ALL_SUITES as SUITES

    scenes = sub.add_parser("scenes", help=_help_line("scenes"))
    ssub = scenes.add_subparsers(dest="scenes_cmd", required=True)
    lst = ssub.add_parser(
        "list", help="scene names, one per line: the packaged scenes, then every suite's"
    )
    lst.add_argument("--suite", choices=SUITES, help="only this suite's scenes")
    lst.add_argument(
        "--json",
        action="store_true",
        help="one JSON object per scene and line: name, n_objects, families, achievable",
    )
    show = ssub.add_parser("show", help="a scene as TOML (usable as a scene file)")
    show.add_argument("name", help=SCENE_HELP)
    scenes.set_defaults(func=_cmd_scenes)


def _add_plan_parser(sub: Any) -> None:
    from utamp_gym.planning.fast_downward import DEFAULT_SEARCH, SEARCH_CONFIGS
    from utamp_gym.planning.methods import DEFAULT_NOISE, METHODS

    plan = sub.add_parser("plan", help=_help_line("plan"))
    plan.add_argument("scene", help=SCENE_HELP)
    plan.add_argument("--method", choices=METHODS, default="utamp2-gt", help=METHOD_HELP)
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
    plan.add_argument("--out", help="write domain.pddl, problem.pddl and plan.txt here")
    plan.add_argument(
        "--explain",
        action="store_true",
        help="if unsolved, name the missing affordance facts that block the scene",
    )
    plan.set_defaults(func=_cmd_plan)


def _add_run_parser(sub: Any) -> None:
    from utamp_gym.planning.methods import METHODS

    run = sub.add_parser("run", help=_help_line("run"))
    run.add_argument("scene", help=SCENE_HELP)
    run.add_argument("--method", choices=METHODS, default="utamp2-gt", help=METHOD_HELP)
    run.add_argument("--seed", type=int, default=0, help="pose noise, IK restarts and OMPL seed")
    run.add_argument("--video", help="write an MP4 (or .gif) of the episode here")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    _add_physics_options(run)
    run.add_argument(
        "--closed-loop",
        action="store_true",
        help="act with the planner policy in the env, replanning from the perceived state",
    )
    run.set_defaults(func=_cmd_run)


def _add_view_parser(sub: Any) -> None:
    view = sub.add_parser(
        "view",
        help=_help_line("view"),
        description="Open SCENE in a window until it is closed. Default: MuJoCo's "
        "interactive viewer on the simulated scene with the Panda at its ready pose (the "
        "physics runs; double-click an object, then Ctrl + right-drag pushes it; Tab and "
        "Shift+Tab show the viewer's panels). --symbolic: the labelled top-down "
        "schematic of the scene's declared state. Needs a display (DISPLAY).",
    )
    view.add_argument("scene", help=SCENE_HELP)
    view.add_argument("--symbolic", action="store_true", help="the labelled schematic instead")
    view.add_argument("--seed", type=int, default=0, help="initial pose noise (physics view)")
    view.set_defaults(func=_cmd_view)


def _add_validate_parser(sub: Any) -> None:
    val = sub.add_parser("validate", help=_help_line("validate"))
    val.add_argument("domain", help="PDDL domain file")
    val.add_argument("problem", help="PDDL problem file")
    val.add_argument("plan", help="plan file: one action per line, e.g. `utamp plan --out`'s")
    val.set_defaults(func=_cmd_validate)


def _add_train_parser(sub: Any) -> None:
    from utamp_gym.rl.cli import add_train_parser

    add_train_parser(sub)


def _add_demos_parser(sub: Any) -> None:
    from utamp_gym.data.cli import add_demos_parser

    add_demos_parser(sub)


SCENE_HELP = "suite scene (pick-place/017), packaged scene or scene-file path"
METHOD_HELP = "where the affordances come from: ground truth, rules, noisy rules, none (UTAMP-1)"
EVAL_HELP = "evaluate planning methods on a suite (the paper's table); `eval merge` joins outputs"
SUBCOMMANDS: tuple[tuple[str, Callable[[Any], None], str], ...] = (
    ("scenes", _add_scenes_parser, "list or show benchmark scenes"),
    ("plan", _add_plan_parser, "plan a scene with Fast Downward"),
    ("run", _add_run_parser, "plan a scene, then execute the plan in MuJoCo physics"),
    (
        "view",
        _add_view_parser,
        "open a scene interactively: MuJoCo's viewer (physics runs), or --symbolic",
    ),
    ("validate", _add_validate_parser, "check a plan against a domain and problem"),
    ("eval", _add_eval_parser, EVAL_HELP),
    (
        "train",
        _add_train_parser,
        "train a baseline: MaskablePPO, PPO, DQN or behaviour cloning (bc)",
    ),
    ("demos", _add_demos_parser, "record planner demonstrations as Minari datasets"),
)
"""(name, what adds its parser, its line in `utamp --help`), in `utamp --help` order."""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every subcommand when `command` is None; otherwise the full parser of
    `command` only, the others listed by name and help line (their options and the modules
    that define them, e.g. the RL and physics stacks, load only when they are the command),
    so that `utamp plan` builds and imports only what planning needs."""
    parser = _Parser(prog="utamp", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    for name, add_parser, help_line in SUBCOMMANDS:
        if command in (None, name):
            add_parser(sub)
        else:  # its name and help line only: never parsed, its own help never shown
            sub.add_parser(name, help=help_line, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one subcommand; returns the exit code (see the module docstring). Without `argv`
    it runs as the `utamp` process, on ``sys.argv``, and the process exits next."""
    started = time.perf_counter()
    if argv is None:
        try:
            return _run(sys.argv[1:], started)
        finally:
            _before_exit()
    return _run(argv, started)


def _before_exit() -> None:
    """Take every live object out of the garbage collector's sight (`gc.freeze`): Python's
    shutdown runs full collections over all of them, the imported modules' included, which
    took ~8 ms of a ~100 ms `utamp plan`; the process ends next, and nothing of it needs
    collecting.

    Not once OMPL is loaded (`utamp run`, `eval`, `train`, `view`: seconds long, so the
    8 ms do not matter): its nanobind bindings print a 28-line leak report on stderr when
    their objects are not collected at shutdown, and frozen objects never are."""
    import gc

    if not any(name == "ompl" or name.startswith("ompl.") for name in sys.modules):
        gc.freeze()


def _run(argv: Sequence[str], started: float) -> int:
    argv = list(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    try:
        args = build_parser(command).parse_args(argv)
        args.started = started
        if args.cmd not in LIGHT_COMMANDS:
            from utamp_gym.env.registry import register_envs

            register_envs()
        return int(args.func(args))
    except UtampError as exc:
        print(f"utamp: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # planner processes were killed on the way out
        print("utamp: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `utamp scenes list | head`
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
