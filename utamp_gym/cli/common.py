"""What the `utamp` subcommands share: the parser class, argument types, help texts and the
physics-execution options (imports nothing of the planning or physics stacks)."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any, NoReturn

MAX_TIMEOUT_S = 86400.0
"""The largest accepted ``--timeout`` (one day): anything longer is a typo."""

SCENE_HELP = "suite scene (pick-place/017), packaged scene or scene-file path"
METHOD_HELP = (
    "where the affordances come from: ground truth, rules, noisy rules, none (UTAMP-1); "
    "default: utamp2-gt, or on a procedural-v2 scene the method its labels assume "
    "(utamp2x-rules, the extended domain)"
)
PAPER_METHOD = "utamp2-gt"  # the default method of every scene but procedural-v2's


def default_method(scene_name: str) -> str:
    """The method `utamp plan` / `utamp run` use when none is given: a procedural-v2
    scene's labelling method (its splits' `achievable` assumes the extended domain), else
    the paper's ``utamp2-gt``."""
    # lazy: keeps `utamp --help` from loading utamp_gym.suites
    from utamp_gym.suites import PROCEDURAL_V2

    if not scene_name.startswith(f"{PROCEDURAL_V2}/"):
        return PAPER_METHOD
    # lazy: utamp_gym.suites.procedural_v2.spec imports numpy (v2 scenes only)
    from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD

    return LABEL_METHOD


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


class Parser(argparse.ArgumentParser):
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
    # lazy: keeps `utamp plan` from loading utamp_gym.backend
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


def add_physics_options(parser: argparse.ArgumentParser) -> None:
    """--pose-noise and --disturbance (physics execution)."""
    # lazy: keeps `utamp plan` from loading utamp_gym.backend
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
