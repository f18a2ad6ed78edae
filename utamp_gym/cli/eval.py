"""`utamp eval`: sweep planning methods over a suite (the paper's table), and `utamp eval merge`
to join output folders."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from utamp_gym.affordances.sources import DEFAULT_NOISE
from utamp_gym.cli import help_line
from utamp_gym.cli.common import add_physics_options, timeout_seconds
from utamp_gym.distributed import EXECUTORS, make_executor
from utamp_gym.errors import UtampError
from utamp_gym.extras import require
from utamp_gym.outputs import output_dir
from utamp_gym.suites import ALL_SUITES as SUITES


def _cmd_eval(args: argparse.Namespace) -> int:
    if args.eval_cmd == "merge":
        return _cmd_eval_merge(args)
    missing = [flag for flag, value in (("--suite", args.suite), ("--out", args.out)) if not value]
    if missing:
        args.eval_parser.error(f"the following arguments are required: {', '.join(missing)}")
    # lazy: keeps `utamp --help` from loading utamp_gym.eval.summary
    from utamp_gym.eval.summary import to_markdown

    # lazy: keeps `utamp --help` from loading utamp_gym.eval.sweep
    from utamp_gym.eval.sweep import SweepConfig, parse_shard, run_sweep, write_outputs

    # lazy: utamp_gym.suites.procedural_v2.spec imports numpy (only utamp eval needs it)
    from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD
    from utamp_gym.suites.procedural_v2.spec import SUITE as V2_SUITE  # lazy: as above

    noise = (args.noise,)
    if args.sweep_noise:
        try:
            noise = tuple(float(p) for p in args.sweep_noise.split(",") if p.strip())
        except ValueError:
            raise UtampError(
                f"--sweep-noise: expected numbers like 0,0.01,0.05, got {args.sweep_noise!r}"
            ) from None
    default = "utamp2-noisy" if args.sweep_noise else "utamp1,utamp2-gt,utamp2-rules,utamp2-noisy"
    if not args.sweep_noise and args.suite and args.suite.startswith(f"{V2_SUITE}/"):
        default = LABEL_METHOD  # the extended domain the split's labels assume
    methods = tuple(m.strip() for m in (args.methods or default).split(",") if m.strip())
    if any(m.startswith("rl:") for m in methods):  # a saved agent: torch, stable-baselines3
        require("utamp eval --methods rl:PATH", "rl")
    if args.executor == "ray":
        require("utamp eval --executor ray", "ray")
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
    # lazy: keeps `utamp --help` from loading utamp_gym.eval.merge
    from utamp_gym.eval.merge import merge_outputs

    # lazy: keeps `utamp --help` from loading utamp_gym.eval.summary
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


def add_parser(sub: Any) -> None:
    """``utamp eval --suite SUITE --out DIR`` (a sweep) and ``utamp eval merge OUT DIR...``.

    argparse has no optional sub-command next to required options, so ``merge`` is an
    optional sub-command and the sweep's required options are checked in `_cmd_eval`.
    """

    ev = sub.add_parser(
        "eval",
        help=help_line("eval"),
        usage="utamp eval --suite SUITE --out DIR [options]\n       utamp eval merge OUT DIR...",
    )
    ev.add_argument("--suite", choices=SUITES, help="required for a sweep")
    ev.add_argument(
        "--methods",
        help="comma-separated: utamp1, utamp2-gt, utamp2-rules, utamp2-noisy, utamp2x-gt, "
        "utamp2x-rules, utamp2-vlm, vlm-planner, rl:PATH (a model.zip from `utamp train`; its "
        "env options come from the model) (default: the first four; on a procedural-v2 suite "
        "utamp2x-rules, the method its labels assume; utamp2-noisy alone with --sweep-noise)",
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
    add_physics_options(ev)
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
