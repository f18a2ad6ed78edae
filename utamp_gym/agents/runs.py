"""Open-loop episodes: plan a scene once, play the plan in the physics env, measure.

`run_episode` is the end-to-end check of one scene (`utamp run`): `plan_scene` gives the
macro actions and `execute_plan` plays them with `OpenLoopPolicy` through the env's one
loop (`utamp_gym.agents.run_policy`), stopping at the first failed step (`execute_plan` alone
replays any given plan, e.g. a VLM's). The env is the physics env of the scene with
``masks="none"``: every plan step reaches the simulator, as the paper's open-loop protocol
has it, whatever the perceived state says; the env's perceptions do not stop the plan
either (it plays on through an anomaly). The episode's world is seeded once,
`run_seed(scene, seed)`, passed to the env's reset as ``world_seed`` (the simulator's
generator, and a second stream of it for injected faults). Success is the env's: every
step succeeded and the goal holds in the perceived state at the end (``info["is_success"]``).
The result also reports what physics measured (the tower on the scene's base, the final
object poses), with planning, execution and per-step timings. Optionally it writes a
headless video of the execution (MP4 via imageio-ffmpeg, or GIF).
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from utamp_gym.agents import OpenLoopPolicy, run_policy
from utamp_gym.backend import DEFAULT_PERCEPTION, DEFAULT_POSE_NOISE, PhysicsBackend
from utamp_gym.env.kitchen import DEFAULT_OBJECTS, UTampKitchenEnv
from utamp_gym.env.symbolic_backend import SymbolicBackend
from utamp_gym.errors import UnknownNameError
from utamp_gym.planning.crosscheck import checking_domain
from utamp_gym.planning.methods import METHODS, PlanOutcome, method_spec, plan_scene
from utamp_gym.scene.model import Scene
from utamp_gym.seeding import run_seed
from utamp_gym.suites import SUITES, resolve_scene
from utamp_gym.tasks.goal import unmet

VIDEO_SIZE = (480, 360)  # width, height
VIDEO_PERIOD = 0.1  # s of simulated time per frame


@dataclass(frozen=True)
class StepRecord:
    """One executed macro action and its timings (s; see `control.Timings`)."""

    step: int
    action: str
    success: bool
    reason: str | None
    timings: dict[str, float]


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of `run_episode`; `to_dict()` gives plain JSON-able data."""

    scene: str
    method: str
    seed: int
    solved: bool
    plan: list[str]
    success: bool
    failure: dict[str, Any] | None  # {step, action, reason}
    final_stack: list[str]  # standing on the tower base (`Scene.tower_base`), bottom -> top
    object_poses: dict[str, list[float]]  # name -> [x, y, z, qw, qx, qy, qz]
    planning_time_s: float
    execution_time_s: float
    wall_time_s: float
    n_faults: int = 0
    steps: list[StepRecord] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Execution:
    """What physics measured while executing one plan (see `execute_plan`)."""

    success: bool
    failure: dict[str, Any] | None  # {step, action, reason}
    final_stack: list[str]
    object_poses: dict[str, list[float]]
    execution_time_s: float
    steps: list[StepRecord]
    n_faults: int = 0

    @property
    def failure_reason(self) -> str:
        """One line: ``""`` on success, else ``step I ACTION: REASON`` or the goal shortfall."""
        f = self.failure
        if f is None:
            return ""
        if f["action"] is None:
            return f["reason"]
        return f"step {f['step']} {f['action']}: {f['reason']}"


def scene_env(
    scene: str | Scene,
    *,
    grounding: str = "physics",
    backend: PhysicsBackend | None = None,
    **options: Any,
) -> UTampKitchenEnv:
    """The env of one scene (`scene`: a suite name, a packaged name, a file path or a `Scene`
    built in code, which the env takes as it is): its suite's action universe and rows, or the
    scene's own; `backend` an existing simulator to act in (the env then uses it instead of
    making one); `options` further env options."""
    name = scene if isinstance(scene, str) else scene.name
    suite = name.split("/", 1)[0] if name.split("/", 1)[0] in SUITES else None
    built = resolve_scene(scene) if isinstance(scene, str) else scene
    names = built.object_names  # a procedural scene: the universe of its own
    objects = DEFAULT_OBJECTS if set(names) <= set(DEFAULT_OBJECTS) else names
    if backend is not None:
        options["backend"] = lambda **_: backend
    return UTampKitchenEnv(
        suite=suite, objects=objects, scene=scene, grounding=grounding, **options
    )


def open_loop_env(
    scene: str | Scene,
    *,
    backend: PhysicsBackend | None = None,
    pose_noise: float = DEFAULT_POSE_NOISE,
    disturbance: float = 0.0,
    perception: str = DEFAULT_PERCEPTION,
    grounding: str = "physics",
    domain: str = "utamp2",
) -> UTampKitchenEnv:
    """The env an open-loop plan of `scene` is played in (module docstring); with `backend`,
    acting in that simulator (`pose_noise` and `perception` are then its own). In
    ``symbolic`` grounding the ground-truth outcome model decides each step (``masks="none"``:
    the U-TAMP-2 precondition under the scene's ground truth); the physics arguments are
    unused. `domain`: the domain the plan was made in; an extended domain's plan plays in an
    env of that domain (its actions, its ground truth), any other in U-TAMP-2's
    (`utamp_gym.planning.crosscheck.checking_domain`)."""
    env_domain = checking_domain(domain)
    # masks "none" exists for U-TAMP-2 only; an extended domain's env masks by its ground
    # truth, so a step it forbids fails on its false literal (in physics too, before acting)
    masks = {"masks": "none"} if env_domain == "utamp2" else {"affordances": "gt"}
    if grounding == "symbolic":
        return scene_env(scene, grounding="symbolic", domain=env_domain, **masks)
    physics = {"pose_noise": pose_noise, "perception": perception} if backend is None else {}
    return scene_env(
        scene, backend=backend, disturbance=disturbance, record_timings=True,
        domain=env_domain, **masks, **physics,
    )  # fmt: skip


def execute_plan(
    scene: Scene | str,
    plan: Sequence[str],
    seed: int = 0,
    video: str | Path | None = None,
    *,
    backend: PhysicsBackend | None = None,
    pose_noise: float = DEFAULT_POSE_NOISE,
    disturbance: float = 0.0,
    perception: str = DEFAULT_PERCEPTION,
    env: UTampKitchenEnv | None = None,
    grounding: str = "physics",
    domain: str = "utamp2",
) -> Execution:
    """Play `plan` on `scene` in the env of `grounding` (`open_loop_env`), stopping at the
    first failed step (open loop; module docstring). `scene`: a name, a file path or a `Scene`.
    A step the env's domain does not have fails there (``not an action of ...``).

    `seed`, mixed with the scene's name (`utamp_gym.seeding.run_seed`), seeds the episode's
    world: initial pose noise, pose estimates, IK restarts and OMPL, and (second stream)
    injected faults; `pose_noise` is the robot's pose-estimation noise (m; ignored when
    `backend` is given: its own applies), `perception` where its pose estimates come from
    (``gaussian`` or ``rgbd``). With `disturbance` p, each executed step is followed with
    probability p by an injected fault. `env`: an `open_loop_env` of the scene to play in
    (e.g. one whose simulator was looked at first), left open; the other physics arguments
    are then its own. `domain`: the domain the plan was made in (`open_loop_env`).
    """
    own = env is None and backend is None
    if env is None:
        env = open_loop_env(
            scene, backend=backend, pose_noise=pose_noise, disturbance=disturbance,
            perception=perception, grounding=grounding, domain=domain,
        )  # fmt: skip
    sim: Any = env.backend
    unknown = _first_unknown(env, plan)  # played up to it, and failed there
    try:
        world = run_seed(env.scenes[0].name, seed)  # independent per (scene, seed)
        with _video(video) as sink:
            sim.frame_sink = sink
            policy: Any = OpenLoopPolicy(env, plan[: len(plan) if unknown is None else unknown])
            if sink is not None:
                policy = _Filmed(policy, sim, sink)
            start = time.perf_counter()
            ep = run_policy(
                env, policy, max_steps=len(plan) + 1, seed=world,
                options={"world_seed": world}, through_termination=True,
            )  # fmt: skip
            if sink is not None:
                sink(sim.render(*VIDEO_SIZE))
            elapsed = time.perf_counter() - start
            steps = _steps(env, ep.records)
            final_stack = sim.stacked_on_tray()
            poses = {n: [float(v) for v in p] for n, p in sim.object_poses().items()}
    finally:
        sim.frame_sink = None
        if own:
            env.close()
    failed = next((s for s in steps if not s.success), None)
    failure = None
    if failed is not None:
        failure = {"step": failed.step, "action": failed.action, "reason": failed.reason}
    elif unknown is not None:
        reason = f"not an action of the env's domain ({env.options.domain})"
        failure = {"step": unknown, "action": plan[unknown], "reason": reason}
    elif not ep.success:
        failure = {"step": len(steps), "action": None, "reason": _shortfall(env, final_stack)}
    n_faults = sum(bool(r[1].get("fault")) for r in ep.records if not r[1]["failure_reason"])
    success = ep.success and failure is None  # a plan cut at an unknown step did not succeed
    return Execution(success, failure, final_stack, poses, elapsed, steps, n_faults)


def run_episode(
    scene: Scene | str,
    method: str = "utamp2-gt",
    seed: int = 0,
    video: str | Path | None = None,
    *,
    backend: PhysicsBackend | None = None,
    pose_noise: float = DEFAULT_POSE_NOISE,
    disturbance: float = 0.0,
    perception: str = DEFAULT_PERCEPTION,
) -> EpisodeResult:
    """Plan `scene` with `method`, play it in the physics env (`execute_plan`) and measure.

    `seed` drives the planner's randomness and the episode's world: the same seed gives the
    same rollout. An unsolved scene is not executed (its poses are measured after reset).
    `pose_noise`, `disturbance` and `perception` as in `execute_plan`. Method
    ``utamp2-perceived`` looks at the scene first: use
    `utamp_gym.eval.perceived.run_perceived_episode`.
    """
    t0 = time.perf_counter()
    outcome = plan_scene(
        resolve_scene(scene) if isinstance(scene, str) else scene, method, seed=seed
    )
    return episode_result(
        scene, outcome, outcome.plan, seed, video, t0, backend, pose_noise, disturbance, perception
    )


def episode_result(
    scene: str | Scene,
    outcome: PlanOutcome,
    plan: Sequence[str],
    seed: int,
    video: str | Path | None,
    t0: float,
    backend: PhysicsBackend | None,
    pose_noise: float,
    disturbance: float,
    perception: str,
    env: UTampKitchenEnv | None = None,
) -> EpisodeResult:
    """Execute `plan` (the world's names of `outcome`'s plan; in `env`, if given) and report
    the episode."""
    ex = execute_plan(
        scene,
        plan if outcome.solved else (),
        seed,
        video,
        backend=backend,
        pose_noise=pose_noise,
        disturbance=disturbance,
        perception=perception,
        env=env,
        domain=method_spec(outcome.method).domain if outcome.method in METHODS else "utamp2",
    )
    failure = ex.failure
    if not outcome.solved:
        failure = {"step": None, "action": None, "reason": f"not planned: {outcome.reason}"}
    return EpisodeResult(
        scene=outcome.scene,
        method=outcome.method,
        seed=seed,
        solved=outcome.solved,
        plan=list(plan),
        success=outcome.solved and failure is None,
        failure=failure,
        final_stack=ex.final_stack,
        object_poses=ex.object_poses,
        planning_time_s=outcome.planning_time_s,
        execution_time_s=ex.execution_time_s,
        wall_time_s=time.perf_counter() - t0,
        n_faults=ex.n_faults,
        steps=ex.steps,
    )


def _shortfall(env: UTampKitchenEnv, final_stack: Sequence[str]) -> str:
    """Why a fully played plan missed the goal: in symbolic grounding the goal literals false
    in the final state; in physics the tower on the base (the tower goal) or the goal
    literals the perceived state lacks."""
    goal, sim = env.goal, env.backend
    if isinstance(sim, SymbolicBackend):
        missing = unmet(goal, sim.state.true_atoms())
        return f"goal not reached: goal literal(s) false at the end: {', '.join(missing)}"
    if goal.template == "tower":
        return f"goal not reached: {env.scene.tower_base} holds {list(final_stack) or 'nothing'}"
    perception = env.perception  # name what the scene's own goal still lacks
    missing = unmet(goal, perception.atoms) if perception is not None else goal.literals
    return f"goal not reached: {', '.join(missing) or 'an object it names is lost'}"


def _first_unknown(env: UTampKitchenEnv, plan: Sequence[str]) -> int | None:
    """The index of the first step of `plan` not in `env`'s action universe (None: none)."""
    for i, step in enumerate(plan):
        try:
            env.universe.index(step)
        except UnknownNameError:
            return i
    return None


def _steps(
    env: UTampKitchenEnv, records: Sequence[tuple[str, Mapping[str, Any], Any]]
) -> list[StepRecord]:
    """The executed steps of an episode's records (action, info, macro result)."""
    out = []
    for i, (action, info, macro) in enumerate(records):
        timings = {} if macro is None else dict(macro.timings)
        reason = info["failure_reason"] or None
        out.append(StepRecord(i, action, not info["failure_reason"], reason, timings))
    return out


class _Filmed:
    """A policy that films the first frame of the episode before its first decision."""

    def __init__(self, policy: Any, sim: Any, sink: Any) -> None:
        self.policy, self.sim, self.sink = policy, sim, sink

    def __call__(self, obs: Any, info: Mapping[str, Any]) -> int:
        if not info.get("action"):
            self.sink(self.sim.render(*VIDEO_SIZE))
        return self.policy(obs, info)


@contextmanager
def _video(path: str | Path | None) -> Iterator[Any]:
    """A frame sink writing `path` (.mp4 through imageio-ffmpeg, .gif otherwise)."""
    if path is None:
        yield None
        return
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fps = round(1 / VIDEO_PERIOD)
    if path.suffix.lower() == ".gif":
        writer = imageio.get_writer(path, mode="I", duration=1000 * VIDEO_PERIOD, loop=0)
    else:
        writer = imageio.get_writer(path, fps=fps, codec="libx264", macro_block_size=8)
    try:
        yield writer.append_data
    finally:
        writer.close()
