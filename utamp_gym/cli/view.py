"""`utamp view`: open a scene in a window (MuJoCo's interactive viewer, or the schematic)."""

from __future__ import annotations

import argparse
from typing import Any

from utamp_gym.cli import help_line
from utamp_gym.cli.common import SCENE_HELP
from utamp_gym.suites import resolve_scene


def _cmd_view(args: argparse.Namespace) -> int:
    """Open a scene in a window until it is closed (MuJoCo's viewer, or the schematic)."""
    # lazy: keeps `utamp --help` from loading utamp_gym.env.viewer
    from utamp_gym.env.viewer import require_display

    scene = resolve_scene(args.scene)
    video = "out/" + scene.name.replace("/", "-") + ".mp4"
    require_display("utamp view", f"utamp run {args.scene} --video {video} (a video, no display)")
    if args.symbolic:
        # lazy: keeps `utamp --help` from loading utamp_gym.env.viewer
        from utamp_gym.env.viewer import show_schematic

        show_schematic(scene)
        return 0
    import mujoco.viewer
    import numpy as np

    # lazy: utamp_gym.sim.backend imports mujoco, ompl, pinocchio
    from utamp_gym.sim.backend import MujocoBackend

    backend = MujocoBackend()
    backend.reset(scene, np.random.default_rng(args.seed))
    # MuJoCo's viewer runs the physics; the servos hold the arm at its ready pose
    mujoco.viewer.launch(backend.model, backend.data, show_left_ui=False, show_right_ui=False)
    return 0


def add_parser(sub: Any) -> None:
    """``utamp view SCENE``."""
    view = sub.add_parser(
        "view",
        help=help_line("view"),
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
