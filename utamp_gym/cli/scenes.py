"""`utamp scenes list|show`: the benchmark's scene names, or one scene as TOML."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from utamp_gym.cli import help_line
from utamp_gym.cli.common import SCENE_HELP
from utamp_gym.scene.io import scene_to_toml
from utamp_gym.suites import (
    ALL_SUITES,
    all_scene_names,
    packaged_scene_names,
    resolve_scene,
    scene_summary,
)
from utamp_gym.suites import LISTED_SUITES as SUITES


def _cmd_scenes(args: argparse.Namespace) -> int:
    if args.scenes_cmd == "list":
        suites = (args.suite,) if args.suite else ALL_SUITES  # v2: the generated splits
        if args.json:  # one JSON document: the list of every scene's record
            records = [r for suite in suites for r in scene_summary(suite)]
            print(json.dumps(records, indent=2))
            return 0
        if not args.suite and not args.jsonl:  # packaged scenes (kitchen-demo), then suites
            for name in packaged_scene_names():
                print(name)
        for suite in suites:
            if args.jsonl:  # one JSON object per line and scene (`| head` keeps whole ones)
                for record in scene_summary(suite):
                    print(json.dumps(record))
            else:
                for name in all_scene_names(suite):
                    print(name)
        return 0
    sys.stdout.write(scene_to_toml(resolve_scene(args.name)))
    return 0


def add_parser(sub: Any) -> None:
    """``utamp scenes list`` and ``utamp scenes show NAME``."""
    scenes = sub.add_parser("scenes", help=help_line("scenes"))
    ssub = scenes.add_subparsers(dest="scenes_cmd", required=True)
    lst = ssub.add_parser(
        "list", help="scene names, one per line: the packaged scenes, then every suite's"
    )
    lst.add_argument("--suite", choices=SUITES, help="only this suite's scenes")
    fmt = lst.add_mutually_exclusive_group()
    fmt.add_argument(
        "--json",
        action="store_true",
        help="one JSON document: a list with an object per scene (name, n_objects, families, "
        "template, instruction, achievable)",
    )
    fmt.add_argument(
        "--jsonl",
        action="store_true",
        help="the same objects as JSON lines: one per scene and line",
    )
    show = ssub.add_parser("show", help="a scene as TOML (usable as a scene file)")
    show.add_argument("name", help=SCENE_HELP)
    scenes.set_defaults(func=_cmd_scenes)
