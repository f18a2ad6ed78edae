"""`utamp validate`: check a plan against a PDDL domain and problem."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from utamp_gym.cli import help_line


def _cmd_validate(args: argparse.Namespace) -> int:
    # lazy: keeps `utamp --help` from loading utamp_gym.symbolic.validate
    from utamp_gym.symbolic.validate import validate_files

    result = validate_files(args.domain, args.problem, args.plan)
    if result.valid:
        print(f"valid: {result.steps_applied} steps reach the goal")
        return 0
    print(result.message, file=sys.stderr)
    return 1


def add_parser(sub: Any) -> None:
    """``utamp validate DOMAIN PROBLEM PLAN``."""
    val = sub.add_parser("validate", help=help_line("validate"))
    val.add_argument("domain", help="PDDL domain file")
    val.add_argument("problem", help="PDDL problem file")
    val.add_argument("plan", help="plan file: one action per line, e.g. `utamp plan --out`'s")
    val.set_defaults(func=_cmd_validate)
