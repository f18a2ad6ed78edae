"""`utamp demos`: planner demonstrations as Minari datasets (wired into `utamp_gym.cli`).

Usage::

    utamp demos --suite SUITE --episodes N --out DIR [--track macro|low-level]
        [--method utamp2-gt] [--seed S] [--grounding symbolic|physics]
        [--masks affordances|geometric|none] [--interface objects|grounded]
        [--slots N] [--domain D] [--affordances A]
        [--image-size H W] [--executor local|ray] [--workers N] [--ray-address A]

    utamp demos export-lerobot --root DIR --dataset ID --out DIR [--repo-id NAME]

The dataset is ``utamp/<suite>-<track>-<method>-v0`` under DIR: read it with
``MINARI_DATASETS_PATH=DIR`` and ``minari.load_dataset(ID)`` (or
`utamp_gym.data.minari_io.load_dataset`). ``export-lerobot`` converts one with the `lerobot`
package, which must be installed (it cannot share this project's environment: see
docs/agents.md).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from utamp_gym.distributed import EXECUTORS, make_executor
from utamp_gym.errors import UtampError
from utamp_gym.extras import require
from utamp_gym.outputs import new_output_dir, output_dir
from utamp_gym.planning.methods import METHODS
from utamp_gym.rl.cli import add_env_option_flags, env_option_flags
from utamp_gym.suites import ALL_SUITES  # the paper's suites and the procedural splits


def _cmd_demos(args: argparse.Namespace) -> int:
    if args.demos_cmd == "export-lerobot":
        require("utamp demos export-lerobot", "data")  # it reads the Minari dataset
        # lazy: keeps `utamp --help` from loading utamp_gym.data.lerobot
        from utamp_gym.data.lerobot import export_lerobot

        new_output_dir(args.out, "--out")  # before the conversion starts

        frames = export_lerobot(args.root, args.dataset, args.out, repo_id=args.repo_id)
        print(f"wrote {frames} frames of {args.dataset} as a LeRobot dataset in {args.out}")
        return 0
    missing = [f for f, v in (("--suite", args.suite), ("--out", args.out)) if not v]
    if missing:
        args.demos_parser.error(f"the following arguments are required: {', '.join(missing)}")
    require("utamp demos", "data")  # the episodes are written as a Minari dataset at the end
    if args.track == "low-level":  # joint commands through utamp_gym.dm
        require("utamp demos --track low-level", "dm")
    if args.executor == "ray":
        require("utamp demos --executor ray", "ray")
    flags = env_option_flags(args, args.interface) if args.track == "macro" else {}
    if args.track != "macro" and any(getattr(args, k) is not None
                                     for k in ("slots", "domain", "affordances")):  # fmt: skip
        raise UtampError("--slots, --domain and --affordances are options of the macro track's "
                         "env (--track macro)")  # fmt: skip
    output_dir(args.out, "--out")  # before any episode is recorded
    # lazy: keeps `utamp --help` from loading utamp_gym.data.record
    from utamp_gym.data.record import record_demos

    workers = args.workers
    if args.executor == "local" and workers is None:
        workers = 0
    executor = make_executor(args.executor, workers=workers, ray_address=args.ray_address)
    options: dict[str, Any] = {}
    if args.track == "macro":
        grounding = args.grounding or "symbolic"
        options = {"grounding": grounding, "masks": args.masks, "interface": args.interface,
                   **flags}  # fmt: skip
    elif args.grounding == "symbolic":
        raise UtampError("--track low-level is always physics (joint commands in MuJoCo)")
    result = record_demos(
        args.suite, args.episodes, args.out, track=args.track, seed=args.seed,
        method=args.method, env_options=options,
        image_size=tuple(args.image_size) if args.image_size else None, executor=executor,
    )  # fmt: skip
    print(
        f"{result.dataset_id}: {result.episodes} episodes, {result.steps} steps, "
        f"{result.successes} reached the goal; written to {result.path}"
    )
    if result.unsolvable:  # by design in the procedural splits: not a failure of the recorder
        shown = "; ".join(f"episode {i}: {r}" for i, r in sorted(result.unsolvable.items())[:3])
        print(f"{len(result.unsolvable)} episode(s) left out, their goal proved unreachable "
              f"({shown})")  # fmt: skip
    if result.failed:
        shown = "; ".join(f"episode {i}: {r}" for i, r in sorted(result.failed.items())[:3])
        print(f"utamp demos: {len(result.failed)} episode(s) not recorded ({shown})",
              file=sys.stderr)  # fmt: skip
        return 1
    return 0


def add_demos_parser(sub: Any) -> None:
    p = sub.add_parser(
        "demos",
        help="record planner demonstrations as Minari datasets (macro or low-level track)",
        usage="utamp demos --suite SUITE --episodes N --out DIR [options]\n"
        "       utamp demos export-lerobot --root DIR --dataset ID --out DIR",
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    p.add_argument("--suite", choices=ALL_SUITES, help="required: the scenes to record")
    p.add_argument("--episodes", type=int, default=10, help="episodes (reset seeds S..S+N-1)")
    p.add_argument("--out", help="required: the folder the dataset is written under")
    p.add_argument(
        "--track",
        choices=("macro", "low-level"),
        default="macro",
        help="macro actions in the Gym env, or joint commands through utamp_gym.dm",
    )
    p.add_argument("--method", choices=METHODS, default="utamp2-gt", help="the planner")
    p.add_argument("--seed", type=int, default=0, help="the first reset seed")
    p.add_argument(
        "--grounding",
        choices=("symbolic", "physics"),
        default=None,
        help="macro track: the env's grounding (default symbolic; low-level: always physics)",
    )
    p.add_argument(
        "--masks",
        choices=("affordances", "geometric", "none"),
        default="geometric",
        help="macro track: the env's mask mode",
    )
    p.add_argument(
        "--interface",
        choices=("objects", "grounded"),
        default="objects",
        help="macro track: the env's spaces (objects: fixed for every suite)",
    )
    add_env_option_flags(p)
    p.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        metavar=("H", "W"),
        help="low-level track: scene-camera image size (default 96 96)",
    )
    p.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="local",
        help="local worker processes (--workers N; default in this process) or Ray",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="local worker processes (default 0: in this process), or the CPUs of a "
        "Ray instance started here",
    )
    p.add_argument(
        "--ray-address",
        default=None,
        help="with --executor ray: the cluster to join (default: RAY_ADDRESS, else "
        "a local Ray instance)",
    )
    p.set_defaults(func=_cmd_demos, demos_parser=p, demos_cmd=None)
    dsub = p.add_subparsers(dest="demos_cmd", metavar="export-lerobot")
    ex = dsub.add_parser(
        "export-lerobot",
        prog="utamp demos export-lerobot",
        help="convert a Minari dataset to a LeRobot dataset (needs the lerobot package)",
    )
    ex.add_argument("--root", required=True, help="the folder the Minari dataset is under")
    ex.add_argument(
        "--dataset", required=True, help="its id, e.g. utamp/pick-place-low-level-utamp2-gt-v0"
    )
    ex.add_argument("--out", required=True, help="the LeRobot dataset's folder (root)")
    ex.add_argument("--repo-id", default=None, help="LeRobot repo id (default: from the id)")
