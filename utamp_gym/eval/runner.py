"""One evaluation run: plan a scene with a method, ground the plan, return one result row.

In either grounding the plan is played open loop in the env by `execute_plan`
(`utamp_gym.agents.runs`, behind `run_episode`: same seed, same rollout), and the env decides:
in ``symbolic`` grounding its outcome model (a step succeeds iff its U-TAMP-2 precondition
holds under the scene's ground truth; the failure reason names the step and the first false
literal), in ``physics`` MuJoCo. The ``valid_gt`` column says whether the whole plan is valid
under the ground-truth U-TAMP-2 model (`check_against_ground_truth`). An unsolved U-TAMP-2
run is explained (`explain`). `run_task` never raises: a crash becomes a failure row.

A method ``rl:PATH`` is a saved RL agent acting in the env of either grounding
(`utamp_gym.rl.harness`: the env options come from the model, episodes have a step budget).
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from utamp_gym.affordances.facts import Fact, Scores
from utamp_gym.affordances.noisy import corrupt_type
from utamp_gym.affordances.sources import DEFAULT_NOISE, detection_rng, scene_types
from utamp_gym.agents.runs import execute_plan, open_loop_env
from utamp_gym.errors import EndpointError, UnknownNameError
from utamp_gym.eval.closed_loop import run_closed_loop
from utamp_gym.eval.explain import EXPLAINED_DOMAINS, explain_unsolvable
from utamp_gym.eval.records import DEFAULT_PERCEPTION, PLAN_SEPARATOR, ResultRow, RunIdentity
from utamp_gym.eval.stages import ATTRIBUTES, failure_stage
from utamp_gym.methods.perceived import attribute_accuracy, mean_accuracy, plan_perceived
from utamp_gym.methods.perceivers import PERCEIVED, check_perceiver, load_perceiver, split_method
from utamp_gym.methods.vlm import RUNNERS, VLM_METHODS
from utamp_gym.methods.vlm_client import VlmClient
from utamp_gym.planning.crosscheck import check_against_ground_truth
from utamp_gym.planning.methods import METHODS, method_spec, plan_scene
from utamp_gym.rl.harness import EnvCache, check_rl_method, run_rl_episode
from utamp_gym.scene.model import Scene
from utamp_gym.suites import resolve_scene, suite_of

EVAL_METHODS = (*METHODS, *VLM_METHODS)
DEFAULT_TIMEOUT = 30.0
RL_METHOD = "rl:PATH"  # a saved agent (utamp train's model.zip)
USER_PERCEIVER = PERCEIVED + ":PACKAGE.MODULE:CLASS"  # a user's perceiver (or an entry point)


def check_method(method: str, suite: str | None = None) -> None:
    """Raise if `method` is neither one of `EVAL_METHODS` nor a usable ``rl:PATH`` model
    (missing, without its env metadata, or trained on another suite), nor
    ``utamp2-perceived:SPEC`` with a loadable perceiver (`utamp_gym.methods.perceivers`)."""
    _, perceiver = split_method(method)
    if perceiver is not None:
        check_perceiver(perceiver)
    elif method.startswith("rl:"):
        check_rl_method(method, suite)
    elif method not in EVAL_METHODS:
        raise UnknownNameError("method", method, (*EVAL_METHODS, RL_METHOD, USER_PERCEIVER))


@dataclass(frozen=True)
class EvalTask(RunIdentity):
    """One scene × method × seed in one grounding (picklable: sent to worker processes)."""

    scene: str
    method: str
    seed: int = 0
    grounding: str = "physics"
    noise: float | None = None  # utamp2-noisy only
    timeout: float = DEFAULT_TIMEOUT
    explain: bool = True
    closed_loop: bool = False
    disturbance: float = 0.0
    pose_noise: float | None = None  # physics only
    perception: str = DEFAULT_PERCEPTION  # physics only: gaussian | rgbd

    def settings(self) -> dict[str, object]:
        """The row columns that repeat the task's settings."""
        return {
            "closed_loop": self.closed_loop,
            "disturbance": self.disturbance,
            "pose_noise": self.pose_noise,
            "perception": self.perception,
        }


@dataclass(frozen=True)
class _Planned:
    solved: bool
    plan: tuple[str, ...]
    planning_time_s: float
    reason: str | None
    scores: Scores | None
    facts: frozenset[Fact] | None  # detected U-TAMP-2 affordances, for explanations
    accuracy: Mapping[str, float] | None = None  # per attribute (detected attributes)
    domain: str = "utamp2"  # the domain planned in (the facts' explanation's)


def _suite_of(name: str) -> str:
    """The suite of a suite scene (``procedural-v1/train/0042`` -> ``procedural-v1/train``);
    ``custom`` for a packaged scene or a scene file."""
    return suite_of(name) or "custom"


def _plan(scene: Scene, task: EvalTask, look: Any = None) -> _Planned:
    """Plan `scene` with the task's method (`look`: the simulator `utamp2-perceived` looks
    through, the one its plan is then played in; None: a world built for the look)."""
    if task.method in VLM_METHODS:
        start = time.perf_counter()
        try:
            out = RUNNERS[task.method](
                scene, VlmClient.from_env(), seed=task.seed, timeout=task.timeout
            )
        except EndpointError as exc:  # unusable answer: a failure, not a crash
            return _Planned(False, (), time.perf_counter() - start, f"VLM: {exc}", None, None)
        return _Planned(
            out.solved, out.plan, out.planning_time_s, out.reason, out.scores, out.facts
        )
    base, spec = split_method(task.method)
    if base == PERCEIVED:
        o, seen = plan_perceived(
            scene, task.seed, timeout=task.timeout, backend=look, perceiver=load_perceiver(spec)
        )
        accuracy = None if seen is None else seen.accuracy
        return _Planned(
            o.solved, o.plan, o.planning_time_s, o.reason, o.affordance_scores, o.facts, accuracy
        )
    noise = DEFAULT_NOISE if task.noise is None else task.noise
    o = plan_scene(scene, task.method, seed=task.seed, timeout=task.timeout, noise=noise)
    domain = method_spec(task.method).domain
    facts = o.facts if domain in EXPLAINED_DOMAINS else None
    scores = o.affordance_scores if task.method != "utamp1" else None
    accuracy = _noisy_accuracy(scene, task.seed, noise) if task.method == "utamp2-noisy" else None
    return _Planned(o.solved, o.plan, o.planning_time_s, o.reason, scores, facts, accuracy, domain)


def _noisy_accuracy(scene: Scene, seed: int, noise: float) -> dict[str, float]:
    """Per-attribute accuracy of the noisy detector's attributes (the same draws as the
    detection: `detection_rng`, types in `scene_types` order)."""
    rng = detection_rng(seed, scene.name)
    noisy = {t.name: corrupt_type(t, noise, rng) for t in scene_types(scene)}
    rows = []
    for o in scene.objects:
        declared = scene.type_of(o.name)
        same = {m: m for m in declared.members}
        rows.append(attribute_accuracy(noisy[declared.name], declared, same))
    return mean_accuracy(rows)


def _run_rl(task: EvalTask, scene: Scene, start: float, envs: EnvCache | None) -> ResultRow:
    ep = run_rl_episode(
        task.method,
        scene.name,
        task.seed,
        task.grounding,
        pose_noise=task.pose_noise,
        disturbance=task.disturbance,
        envs=envs,
    )
    return _row(
        task,
        scene.name,
        scene.n_objects,
        start,
        solved=ep.success,
        success=ep.success,
        failure_reason=ep.reason,
        plan_length=len(ep.actions),
        planning_time_s=ep.decision_time_s,
        execution_time_s=ep.execution_time_s,
        plan=PLAN_SEPARATOR.join(ep.actions),
        n_faults=ep.n_faults,
    )


def _run_closed_loop(task: EvalTask, start: float) -> ResultRow:
    scene = resolve_scene(task.scene)
    noise = DEFAULT_NOISE if task.noise is None else task.noise
    out = run_closed_loop(
        task.scene,
        task.method,
        seed=task.seed,
        grounding=task.grounding,
        disturbance=task.disturbance,
        pose_noise=task.pose_noise,
        noise=noise,
        timeout=task.timeout,
        perception=task.perception,
    )
    return _row(
        task,
        scene.name,
        scene.n_objects,
        start,
        solved=bool(out.actions) or out.success,
        success=out.success,
        failure_reason=out.failure,
        plan_length=len(out.actions),
        planning_time_s=out.planning_time_s,
        execution_time_s=out.execution_time_s,
        plan=PLAN_SEPARATOR.join(out.actions),
        n_faults=out.n_faults,
        n_replans=out.n_replans,
        n_weighings=out.n_weighings,
        n_looks=out.n_looks,
    )


def _run(task: EvalTask, start: float, envs: EnvCache | None) -> ResultRow:
    if task.method.startswith("rl:"):  # a saved agent acting in the env (always closed loop)
        return _run_rl(task, resolve_scene(task.scene), start, envs)
    if task.closed_loop:
        return _run_closed_loop(task, start)
    scene = resolve_scene(task.scene)
    env = None  # the env the plan is played in, made before planning to look through
    if split_method(task.method)[0] == PERCEIVED:
        env = _open_loop_env(task)
    try:
        return _run_open_loop(task, scene, start, env)
    finally:
        if env is not None:
            env.close()


def _open_loop_env(task: EvalTask) -> Any:
    if task.grounding == "symbolic":
        return open_loop_env(task.scene, grounding="symbolic")
    assert task.pose_noise is not None
    return open_loop_env(
        task.scene, pose_noise=task.pose_noise, disturbance=task.disturbance,
        perception=task.perception,
    )  # fmt: skip


def _run_open_loop(task: EvalTask, scene: Scene, start: float, env: Any) -> ResultRow:
    """The open-loop protocol: plan once, then play the plan in the env of the grounding."""
    exec_time, n_faults = 0.0, 0
    planned = _plan(scene, task, None if env is None else env.backend)
    success, failure = False, ""
    valid_gt = None
    plan = planned.plan
    if planned.solved:  # the plan played open loop in the env (`OpenLoopPolicy`)
        valid_gt = check_against_ground_truth(scene, plan, planned.domain).valid
        physics = {} if task.grounding == "symbolic" else {
            "pose_noise": task.pose_noise, "disturbance": task.disturbance,
            "perception": task.perception,
        }  # fmt: skip
        ex = execute_plan(
            task.scene, plan, task.seed, env=env, grounding=task.grounding,
            domain=planned.domain, **physics,
        )  # fmt: skip
        success, failure, exec_time = ex.success, ex.failure_reason, ex.execution_time_s
        n_faults = ex.n_faults
    else:
        failure = f"not solved: {planned.reason}"
        if task.explain and planned.facts is not None:
            why = explain_unsolvable(scene, planned.facts, domain=planned.domain)
            failure += "; " + why.message
    s = planned.scores
    return _row(
        task,
        scene.name,
        scene.n_objects,
        start,
        solved=planned.solved,
        success=bool(success),
        failure_reason="" if success else failure,
        plan_length=len(planned.plan),
        planning_time_s=planned.planning_time_s,
        execution_time_s=exec_time,
        affordance_precision=None if s is None else s.precision,
        affordance_recall=None if s is None else s.recall,
        affordance_f1=None if s is None else s.f1,
        valid_gt=valid_gt,
        plan=PLAN_SEPARATOR.join(plan),
        n_faults=n_faults,
        **_accuracy_columns(planned.accuracy),
    )


def _accuracy_columns(accuracy: Mapping[str, float] | None) -> dict[str, float | None]:
    if accuracy is None:
        return {}
    return {f"acc_{a}": float(accuracy[a]) for a in ATTRIBUTES}


def failure_row(task: EvalTask, reason: str, wall_time_s: float = 0.0) -> ResultRow:
    """The row recorded for a run that crashed (an exception, or its worker process died)."""
    try:
        n_objects = resolve_scene(task.scene).n_objects
    except Exception:
        n_objects = 0
    return _row(
        task,
        task.scene,
        n_objects,
        None,
        solved=False,
        success=False,
        failure_reason=reason,
        plan_length=0,
        planning_time_s=None,
        execution_time_s=0.0,
        wall_time_s=wall_time_s,
        crashed=True,
    )


def _row(
    task: EvalTask, scene: str, n_objects: int, start: float | None, **outcome: Any
) -> ResultRow:
    """The row of `task`: its identity and settings columns, the wall time since `start`
    (if given), affordance scores None unless `outcome` has them, and `outcome`."""
    columns: dict[str, Any] = {
        "affordance_precision": None,
        "affordance_recall": None,
        "affordance_f1": None,
    }
    if start is not None:
        columns["wall_time_s"] = time.perf_counter() - start
    columns.update(outcome)
    columns.setdefault(
        "failure_stage",
        failure_stage(
            task.method,
            success=bool(columns.get("success")),
            crashed=bool(columns.get("crashed")),
            solved=bool(columns.get("solved")),
            valid_gt=columns.get("valid_gt"),
            affordance_f1=columns.get("affordance_f1"),
            grounding=task.grounding,
        ),
    )
    return ResultRow(
        scene=scene,
        suite=_suite_of(scene),
        n_objects=n_objects,
        method=task.method,
        seed=task.seed,
        grounding=task.grounding,
        noise=task.noise,
        **columns,
        **task.settings(),
    )


def run_task(task: EvalTask, envs: EnvCache | None = None) -> ResultRow:
    """Run one task; any exception becomes a failure row (`crashed`) with its reason.
    `envs`: the caller's `EnvCache` an ``rl:PATH`` task in symbolic grounding takes its env
    from (a loop over tasks in one process owns one); without it the task makes its own."""
    start = time.perf_counter()
    try:
        return _run(task, start, envs)
    except Exception as exc:
        where = traceback.extract_tb(exc.__traceback__)[-1]
        reason = f"crashed: {type(exc).__name__}: {exc} (at {where.name}:{where.lineno})"
        return failure_row(task, reason, time.perf_counter() - start)
