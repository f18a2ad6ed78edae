"""Where the simulated time of an episode goes: `mj_step` calls per macro phase.

Imported by `physics_speed.py`'s worker, which runs in the code under test (this tree or
an earlier commit's worktree), so it relies only on what both have: `run_episode` and the
names of the functions that step the physics (`ArmDriver.transfer`, `move_line`,
`close_gripper`, `open_gripper`, `payload.hold_and_measure`, `measure.settle_objects`,
`faults.push` / `drop`) and of the skills that call them (`_grasp`, `pick`, `place`,
`slide`, `_release_and_retreat`). `Meter` replaces `mujoco.mj_step` with a wrapper that
counts steps (an ``nstep`` call counts ``nstep``), the wall time inside them and the
contacts after each call (counted for each of its steps); with
``phases=True`` it also walks the Python stack at every call and books the steps to the
innermost phase function it finds (a few µs a call: use it in a separate pass from the
timed one).

    python benchmarks/physics_phases.py pick-place/105 [--seed 0]
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
from types import FrameType
from typing import Any

import mujoco

#: phases in the order a pick and a place go through them (the report's row order)
PHASES = (
    "to pre-grasp",
    "approach",
    "closing",
    "lift",
    "transport",
    "lower",
    "opening",
    "retreat",
    "slide",
    "load checks",
    "settle",
    "arm settle",
    "fault",
    "reset",
    "other",
)
_STEPPERS = frozenset(
    {
        "transfer",
        "move_line",
        "close_gripper",
        "open_gripper",
        "hold_and_measure",
        "settle_objects",
        "push",
        "drop",
    }
)
#: (stepping function, the skill function that called it) -> phase
_IN_SKILL = {
    ("transfer", "_grasp"): "to pre-grasp",
    ("transfer", "place"): "transport",
    ("move_line", "_grasp"): "approach",
    ("move_line", "pick"): "lift",
    ("move_line", "place"): "lower",
    ("move_line", "_release_and_retreat"): "retreat",
    ("move_line", "slide"): "slide",
}
_ALONE = {
    "close_gripper": "closing",
    "open_gripper": "opening",
    "hold_and_measure": "load checks",
    "push": "fault",
    "drop": "fault",
}


def phase_of(frame: FrameType | None) -> str:
    """The macro phase of the `mj_step` call made from `frame` (see `PHASES`)."""
    names: list[str] = []
    while frame is not None:
        names.append(frame.f_code.co_name)
        frame = frame.f_back
    stepper = next((k for k, n in enumerate(names) if n in _STEPPERS), None)
    if stepper is None:
        return "other"
    name = names[stepper]
    if name == "settle_objects":
        return "reset" if "reset" in names else "settle"
    if name in _ALONE:
        return _ALONE[name]
    if "settle_arm" in names[:stepper]:
        return "arm settle"
    for caller in names[stepper + 1 :]:
        if (name, caller) in _IN_SKILL:
            return _IN_SKILL[(name, caller)]
    return "other"


class Meter:
    """Counts `mj_step` calls (and books them to phases) while installed (a context)."""

    def __init__(self, *, phases: bool = False) -> None:
        self.phases = phases
        self.steps = 0
        self.step_wall_s = 0.0
        self.contacts = 0  # sum over steps of the contacts after the call
        self.by_phase: collections.Counter[str] = collections.Counter()
        self._orig = mujoco.mj_step

    def __enter__(self) -> Meter:
        orig, clock = self._orig, time.perf_counter

        def mj_step(model: Any, data: Any, nstep: int = 1) -> None:
            if self.phases:
                self.by_phase[phase_of(sys._getframe(1))] += nstep
            t0 = clock()
            orig(model, data, nstep=nstep)
            self.step_wall_s += clock() - t0
            self.steps += nstep
            self.contacts += data.ncon * nstep

        mujoco.mj_step = mj_step
        return self

    def __exit__(self, *exc: object) -> None:
        mujoco.mj_step = self._orig


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--seed", type=int, default=0)
    return ap


def main() -> None:
    args = build_parser().parse_args()
    from utamp_gym.agents.runs import run_episode

    with Meter(phases=True) as meter:
        r = run_episode(args.scene, seed=args.seed)
    dt = 0.002
    print(f"{args.scene} seed {args.seed}: {'ok' if r.success else r.failure}")
    print(f"{meter.steps} mj_step calls, {meter.steps * dt:.2f} simulated s")
    for phase in PHASES:
        n = meter.by_phase.get(phase, 0)
        if n:
            print(f"  {phase:14} {n * dt:7.2f} s  {100 * n / meter.steps:5.1f} %")


if __name__ == "__main__":
    main()
