"""What one `mj_step` costs, and what would make it cheaper.

Runs one episode (default pick-place/105, five objects) on this code and keeps the physics
state every half simulated second. Then, from every kept state, it steps copies of the
episode's model under variants of the physics options: as run (sleeping islands on), every
body awake (the earlier default), the arm links 0-7 without collisions (only hand and
fingers can touch the scene), and solver settings (dense Jacobian, CG, a looser tolerance).
Each state is stepped `--warmup` steps untimed (restoring a state wakes every island; the
resting ones fall asleep again within 10 steps), then `--steps` steps timed with the
controls as they were. Rounds interleave the variants; each variant's time is the best of
`--rounds`. Prints µs per step, contacts, constraint rows and solver iterations per step,
and writes ``<out>.md`` for the docs (`docs/physics-speed.md`).

    python benchmarks/physics_step_cost.py [--scene pick-place/105] [--seed 0] [--rounds 5]
        [--out docs/results/physics_step_cost]
"""

from __future__ import annotations

import argparse
import copy
import os
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np

from utamp_gym.provenance import commit, write_markdown

ROOT = Path(__file__).resolve().parent.parent
STATE = mujoco.mjtState.mjSTATE_INTEGRATION
SLEEP = int(mujoco.mjtEnableBit.mjENBL_SLEEP)


def record(scene: str, seed: int, every_s: float) -> tuple[mujoco.MjModel, list[np.ndarray], set]:
    """(model, states every `every_s` simulated s, arm link geom ids) of one episode."""
    from utamp_gym.agents.runs import run_episode
    from utamp_gym.sim.backend import MujocoBackend

    states: list[np.ndarray] = []
    orig = mujoco.mj_step
    kept: dict[str, mujoco.MjModel] = {}
    every = 0

    def mj_step(model: mujoco.MjModel, data: mujoco.MjData, nstep: int = 1) -> None:
        nonlocal every
        every = every or round(every_s / model.opt.timestep)
        for _ in range(nstep):
            orig(model, data)
            if round(data.time / model.opt.timestep) % every == 0:
                state = np.empty(mujoco.mj_stateSize(model, STATE))
                mujoco.mj_getState(model, data, state, STATE)
                states.append(state)
                kept["model"] = model

    backend = MujocoBackend()
    mujoco.mj_step = mj_step
    try:
        result = run_episode(scene, seed=seed, backend=backend)
        ids = backend.state.arm.ids
        model = kept["model"]
        arm_links = {
            int(g)
            for g in ids.geom_ids
            if int(model.geom_bodyid[g]) not in set(ids.hand_body_ids.tolist())
        }
    finally:
        mujoco.mj_step = orig
        backend.close()
    print(f"{scene} seed {seed}: {'ok' if result.success else result.failure}, "
          f"{len(states)} states kept")  # fmt: skip
    return model, states, arm_links


def variants(arm_links: set) -> dict[str, tuple[Callable[[mujoco.MjModel], None], str]]:
    """name -> (change to a model copy, what it does to the physics)."""

    def awake(m: mujoco.MjModel) -> None:
        m.opt.enableflags &= ~SLEEP

    def no_arm_contacts(m: mujoco.MjModel) -> None:
        awake(m)
        for g in arm_links:
            m.geom_contype[g] = m.geom_conaffinity[g] = 0

    def solver(**kw: object) -> Callable[[mujoco.MjModel], None]:
        def change(m: mujoco.MjModel) -> None:
            awake(m)
            for k, v in kw.items():
                setattr(m.opt, k, v)

        return change

    return {
        "as run: sleeping islands": (lambda m: None, "objects at rest frozen until touched"),
        "every body awake (before)": (awake, "reference"),
        "awake, arm links 0-7 without contacts": (
            no_arm_contacts,
            "an arm link could pass through the scene",
        ),
        "awake, dense Jacobian": (solver(jacobian=mujoco.mjtJacobian.mjJAC_DENSE), "none"),
        "awake, solver tolerance 1e-6": (solver(tolerance=1e-6), "looser convergence"),
        "awake, CG solver": (solver(solver=mujoco.mjtSolver.mjSOL_CG), "another solver"),
    }


def measure(
    model: mujoco.MjModel, states: list[np.ndarray], warmup: int, steps: int
) -> tuple[float, float, float, float]:
    """(µs per step, contacts, constraint rows, solver iterations per step) over the states."""
    data = mujoco.MjData(model)
    wall = contacts = rows = iters = 0.0
    for state in states:
        mujoco.mj_setState(model, data, state, STATE)
        mujoco.mj_step(model, data, nstep=warmup)
        t0 = time.perf_counter()
        mujoco.mj_step(model, data, nstep=steps)
        wall += time.perf_counter() - t0
        contacts, rows, iters = contacts + data.ncon, rows + data.nefc, iters + data.solver_niter[0]
    n = len(states)
    return 1e6 * wall / (n * steps), contacts / n, rows / n, iters / n


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="pick-place/105")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--every", type=float, default=0.5, help="simulated s between kept states")
    ap.add_argument("--warmup", type=int, default=50)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "physics_step_cost"))
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    load = os.getloadavg()
    model, states, arm_links = record(args.scene, args.seed, args.every)
    table = variants(arm_links)
    models = {}
    for name, (change, _) in table.items():
        models[name] = copy.deepcopy(model)
        change(models[name])
    best: dict[str, tuple[float, float, float, float]] = {}
    for _ in range(args.rounds):
        for name, m in models.items():
            r = measure(m, states, args.warmup, args.steps)
            if name not in best or r[0] < best[name][0]:
                best[name] = r
    ref = best["every body awake (before)"][0]
    lines = [
        "| physics options | µs per step | vs awake | contacts | constraint rows "
        "| solver iterations | what it changes |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, (us, con, rows, it) in best.items():
        lines.append(
            f"| {name} | {us:.1f} | {us / ref:.2f}× | {con:.1f} | {rows:.0f} | {it:.2f} "
            f"| {table[name][1]} |"
        )
    lines += [
        "",
        f"Per step, from {len(states)} states of `{args.scene}` (seed {args.seed}) kept every "
        f"{args.every:g} simulated s: {args.steps} steps each after {args.warmup} untimed, best "
        f"of {args.rounds} interleaved rounds; load average {load[0]:.1f} at the start. "
        "Generated by `benchmarks/physics_step_cost.py`.",
    ]
    text = "\n".join(lines) + "\n"
    print("\n" + text)
    out = Path(args.out).with_suffix(".md")
    out.parent.mkdir(parents=True, exist_ok=True)
    write_markdown(out, text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
