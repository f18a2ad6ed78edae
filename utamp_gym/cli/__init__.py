"""The `utamp` command line: scenes, plan, validate, run, view, eval, train, demos.

Exit codes: 0 success (also for `plan` when the scene is unsolvable or the planner timed out:
see `solved` and `timed_out`), 1 an invalid plan (`validate`) or an `eval` sweep with crashed
runs (named on stderr; their rows are in results.csv and run again on resume), 2 bad input
(unknown scene, malformed file, bad option value, a missing optional extra, a failed training
seed, ...), 130 interrupted (Ctrl-C).

Each subcommand imports what it needs when it runs; `utamp plan` imports neither Gymnasium
nor the physics stack (the RL parser and the env registration load only for the
subcommands that use them).

One module per subcommand, each with its parser (``add_parser``) and its command
(``_cmd_*``): `scenes`, `plan`, `run`, `view`, `validate`, `eval` here, ``train`` and
``demos`` beside their packages (`utamp_gym.rl.cli`, `utamp_gym.data.cli`); `common` holds
what they share. This module assembles the parser, importing only the module of the command
that runs, and runs it.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from utamp_gym.cli.common import (
    MAX_TIMEOUT_S,
    METHOD_HELP,
    SCENE_HELP,
    Parser,
    timeout_seconds,
)
from utamp_gym.errors import UtampError

if TYPE_CHECKING:
    import argparse

__all__ = [
    "EVAL_HELP",
    "LIGHT_COMMANDS",
    "MAX_TIMEOUT_S",
    "METHOD_HELP",
    "SCENE_HELP",
    "SUBCOMMANDS",
    "build_parser",
    "help_line",
    "main",
    "timeout_seconds",
]

LIGHT_COMMANDS = ("scenes", "plan", "validate")
"""Subcommands that never build an env: the Gymnasium env ids are not registered for them."""
EVAL_HELP = "evaluate planning methods on a suite (the paper's table); `eval merge` joins outputs"
SUBCOMMANDS: tuple[tuple[str, str, str], ...] = (
    ("scenes", "utamp_gym.cli.scenes:add_parser", "list or show benchmark scenes"),
    ("plan", "utamp_gym.cli.plan:add_parser", "plan a scene with Fast Downward"),
    (
        "run",
        "utamp_gym.cli.run:add_parser",
        "plan a scene, then execute the plan in MuJoCo physics",
    ),
    (
        "view",
        "utamp_gym.cli.view:add_parser",
        "open a scene interactively: MuJoCo's viewer (physics runs), or --symbolic",
    ),
    ("validate", "utamp_gym.cli.validate:add_parser", "check a plan against a domain and problem"),
    ("eval", "utamp_gym.cli.eval:add_parser", EVAL_HELP),
    (
        "train",
        "utamp_gym.rl.cli:add_train_parser",
        "train a baseline: MaskablePPO, PPO, DQN or behaviour cloning (bc)",
    ),
    (
        "demos",
        "utamp_gym.data.cli:add_demos_parser",
        "record planner demonstrations as Minari datasets",
    ),
)
"""(name, ``module:function`` that adds its parser, its line in `utamp --help`), in
`utamp --help` order."""


def help_line(command: str) -> str:
    """`command`'s line in `utamp --help`."""
    return next(line for name, _, line in SUBCOMMANDS if name == command)


def _adder(target: str) -> Callable[[Any], object]:
    """The function named by ``module:function``, its module imported now."""
    module, _, function = target.partition(":")
    # `__import__`, not `importlib.import_module`: the same import, but one that
    # ``python -X importtime`` reports (it sees the import statement's machinery only)
    adder: Callable[[Any], object] = getattr(__import__(module, fromlist=[function]), function)
    return adder


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every subcommand when `command` is None; otherwise the full parser of
    `command` only, the others listed by name and help line (their options and the modules
    that define them, e.g. the RL and physics stacks, load only when they are the command),
    so that `utamp plan` builds and imports only what planning needs."""
    parser = Parser(prog="utamp", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    for name, add_parser, line in SUBCOMMANDS:
        if command in (None, name):
            _adder(add_parser)(sub)
        else:  # its name and help line only: never parsed, its own help never shown
            sub.add_parser(name, help=line, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one subcommand; returns the exit code (see the module docstring). Without `argv`
    it runs as the `utamp` process, on ``sys.argv``, and the process exits next."""
    started = time.perf_counter()
    if argv is None:
        try:
            return _run(sys.argv[1:], started, process=True)
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


def _no_collections() -> None:
    """Turn the cyclic garbage collector off for the rest of a light command's process
    (`gc.disable`): importing the planner and planning set off ~30 collections, ~5 % of a
    ~80 ms `utamp plan`, each walking the objects just made (modules, classes, the ground
    task: the grounder already pauses it, `StatePlanner`), which are garbage only when the
    process ends next. Reference counting still frees everything that is not a cycle."""
    import gc

    gc.disable()


def _run(argv: Sequence[str], started: float, *, process: bool = False) -> int:
    """Run `argv`'s subcommand; `process`: as the `utamp` process (it ends next)."""
    argv = list(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    if process and command in LIGHT_COMMANDS:
        _no_collections()
    try:
        args = build_parser(command).parse_args(argv)
        args.started = started
        if args.cmd not in LIGHT_COMMANDS:
            # lazy: keeps the light commands (utamp plan, ...) from loading gymnasium
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
