"""A saved agent as an evaluation method: ``utamp eval --methods rl:PATH``.

Why: learned agents and planners are compared on the same scenes, seeds and groundings, with
rows side by side in ``results.csv``. An ``rl:PATH`` run builds the env the model was trained
on from its `ModelMeta` (env id, ``masks``), in the eval's grounding, resets it to the task's
scene and seed, and lets the deterministic policy act (choosing among the actions the mask
shows) until the goal, a dead end, or the step budget.

Step budget: `STEPS_PER_OBJECT` steps per object of the scene (20 for two objects, 50 for
five), about four times the longest optimal plan (12 steps for five objects), so an agent
gets room to recover from failed actions but a wandering one does not run the 100-step
training limit through physics.

A row's `plan` lists the actions taken (failed ones too), `plan_length` their number,
`planning_time_s` the time spent choosing them (policy inference) and `execution_time_s` the
time spent in the env's steps (the simulator in physics grounding).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from utamp_gym import suites
from utamp_gym.agents.episode import run_policy
from utamp_gym.env.object_space import slots_for_actions
from utamp_gym.env.options import EnvOptions
from utamp_gym.env.registry import register_envs
from utamp_gym.rl.envs import n_fluents
from utamp_gym.rl.policy import load_rl_policy
from utamp_gym.rl.saved import ModelError, ModelMeta, check_model, check_spaces, read_meta
from utamp_gym.seeding import run_seed
from utamp_gym.suites import resolve_scene

if TYPE_CHECKING:
    from utamp_gym.rl.policy import RLPolicy

RL_PREFIX = "rl:"
STEPS_PER_OBJECT = 10


def is_rl_method(method: str) -> bool:
    return method.startswith(RL_PREFIX)


def model_path(method: str) -> Path:
    """The model zip of an ``rl:PATH`` method."""
    path = method[len(RL_PREFIX) :].strip()
    if not path:
        raise ModelError("method 'rl:' needs a model path, e.g. rl:runs/rl/model.zip")
    return Path(path).expanduser()


def check_rl_method(method: str, suite: str | None = None, *, spaces: bool = True) -> ModelMeta:
    """Fail fast (`ModelError`) if the model is missing, has no metadata, was trained on
    another suite or (`spaces`) does not fit its env's action and observation sizes today
    (checked on the symbolic env: both groundings share the spaces); returns its metadata."""
    path = model_path(method)
    meta = read_meta(path)
    check_model(meta, path, suite=suite, same_actions=shares_actions(meta, suite))
    check_slots(meta, path, suite)
    if spaces:
        import gymnasium as gym

        register_envs()  # explicitly: a worker process may have skipped it on import

        try:
            env = gym.make(meta.env_id, grounding="symbolic", **model_env_options(meta))
        except (gym.error.Error, ValueError) as exc:
            raise ModelError(f"{path}: cannot make its env {meta.env_id} ({exc})") from None
        check_spaces(meta, path, int(env.action_space.n), n_fluents(env))  # type: ignore[attr-defined]
        env.close()
    return meta


def model_slots(meta: ModelMeta) -> int | None:
    """An objects-interface model's object slots: its env option ``slots``, else the count its
    action space was made for (a model saved without the option took the env's default);
    None for a grounded model."""
    if meta.env_options.get("interface") != "objects":
        return None
    given = meta.env_options.get("slots")
    return int(given) if given else slots_for_actions(meta.n_actions)


def model_env_options(meta: ModelMeta) -> dict[str, Any]:
    """The env options a model acts in: its own, with an objects-interface model's slot count
    explicit (`model_slots`: a suite of larger scenes would otherwise widen the spaces)."""
    slots = model_slots(meta)
    return meta.env_kwargs if slots is None else {**meta.env_kwargs, "slots": slots}


def check_slots(meta: ModelMeta, path: str | Path, suite: str | None) -> None:
    """Raise `ModelError` if `suite` has a scene with more objects than the model's slots."""
    slots = model_slots(meta)
    if slots is None or suite is None or _suite_of(f"{suite}/") != suite:
        return
    big = max(suites.suite_scenes(suite), key=lambda s: s.n_objects, default=None)
    if big is not None and big.n_objects > slots:
        raise ModelError(
            f"{path} acts on {slots} object slots, but scene '{big.name}' of {suite} has "
            f"{big.n_objects} objects: evaluate it on scenes of at most {slots} objects, or "
            f"train with --slots {big.n_objects} (utamp train --interface objects --slots N)"
        )


def _suite_of(scene: str) -> str | None:
    """The suite (or procedural split) a scene name belongs to, if any."""
    every = getattr(suites, "ALL_SUITES", suites.SUITES)  # with the procedural splits
    return max((s for s in every if scene.startswith(f"{s}/")), key=len, default=None)


def _suite_choice(suite: str) -> dict[str, Any]:
    """The env options that select `suite` (a procedural env takes its split, not a suite)."""
    if suite in getattr(suites, "PROCEDURAL_SUITES", ()):
        return {"suite": None, "split": suite.rsplit("/", 1)[1]}
    return {"suite": suite, "split": None}


def shares_actions(meta: ModelMeta, suite: str | None) -> bool:
    """Whether a grounded model's action ids mean the same actions on `suite` as in training:
    its env on that suite grounds the same action universe (all procedural-v1 splits share
    one; an objects-interface model's ids mean the same everywhere). Decided from the env
    options alone, without grounding anything."""
    if suite is None or suite == meta.suite or meta.env_options.get("interface") == "objects":
        return True
    import gymnasium as gym

    register_envs()
    try:
        spec = gym.spec(meta.env_id)
    except gym.error.Error:
        return False
    base = {"suite": None, "objects": ("base",), **(spec.kwargs or {}), **meta.env_options}
    base.pop("interface", None)
    allowed = {f.name for f in fields(EnvOptions)}
    try:
        trained = EnvOptions(**{k: v for k, v in base.items() if k in allowed})
        there = EnvOptions(**{k: v for k, v in {**base, **_suite_choice(suite)}.items()
                              if k in allowed})  # fmt: skip
    except (ValueError, TypeError):
        return False
    return trained.universe_key() == there.universe_key()


def suite_options(scene: str) -> dict[str, Any]:
    """Env options that put `scene`'s suite under an objects-interface agent (it acts on any
    suite): the suite and, as pose rows, every object name of the suite's scenes."""
    suite = _suite_of(scene)
    if suite is None:
        return {}
    names = list(dict.fromkeys(n for s in suites.suite_scenes(suite) for n in s.object_names))
    return {**_suite_choice(suite), "objects": names}


def step_budget(n_objects: int) -> int:
    """Steps an agent gets for a scene (see the module docstring)."""
    return STEPS_PER_OBJECT * n_objects


@dataclass(frozen=True)
class RLEpisode:
    """One evaluated episode of a saved agent."""

    success: bool
    reason: str  # "" on success
    actions: tuple[str, ...]
    failed_actions: int
    decision_time_s: float
    execution_time_s: float
    n_faults: int = 0  # injected faults (physics grounding with disturbance)


@lru_cache(maxsize=2)
def _load(path: str, mtime_ns: int) -> RLPolicy:
    """The policy of a model file (cached per process: a sweep runs it on many scenes)."""
    return load_rl_policy(path)


def run_rl_episode(
    method: str,
    scene: str,
    seed: int,
    grounding: str,
    *,
    pose_noise: float | None = None,
    disturbance: float = 0.0,
    envs: EnvCache | None = None,
) -> RLEpisode:
    """Run the ``rl:PATH`` agent on one scene (see the module docstring). `envs`: in symbolic
    grounding, the caller's `EnvCache` to take the env from (left open), else the episode
    makes its own env and closes it."""

    register_envs()  # explicitly: a worker process may have skipped it on import

    path = model_path(method)
    meta = check_rl_method(method, spaces=False)  # checked below on the env itself
    policy = _load(str(path.resolve()), path.stat().st_mtime_ns)
    options: dict[str, Any] = {**model_env_options(meta), "disturbance": disturbance}
    if meta.env_options.get("interface") == "objects":
        options.update(suite_options(scene))
    else:  # a grounded model: on another suite of its action universe (checked), that suite
        suite = _suite_of(scene)
        check_model(meta, path, suite=suite, same_actions=shares_actions(meta, suite))
        if suite is not None and suite != meta.suite:
            options.update(_suite_choice(suite))
    if grounding == "physics" and pose_noise is not None:
        options["pose_noise"] = pose_noise
    options.update(reward_shaping=False, terminate_on_failure=False, record_timings=False)
    kept = envs is not None and grounding == "symbolic"
    if kept:
        env = envs.get(meta.env_id, grounding, options)  # type: ignore[union-attr]
    else:
        import gymnasium as gym

        env = gym.make(meta.env_id, grounding=grounding, **options)
    try:
        n_actions = int(env.action_space.n)  # type: ignore[attr-defined]
        check_spaces(meta, path, n_actions, n_fluents(env))
        # seeded per (scene, seed), as the planners' runs are; the one episode loop
        budget = step_budget(resolve_scene(scene).n_objects)
        policy.reset()
        ep = run_policy(
            env,
            policy,
            max_steps=budget,
            seed=run_seed(resolve_scene(scene).name, seed),
            options={"scene": scene},
        )
        why = ""
        if ep.ended == "budget":
            why = f"budget exhausted: no goal in {budget} steps ({ep.n_failed} failed)"
            if ep.last_failure:
                why += f"; last failure: {ep.last_failure}"
        elif not ep.success:
            why = _terminal_reason(dict(ep.info), len(ep.actions))
        return RLEpisode(
            ep.success, why, ep.actions, ep.n_failed, ep.decision_s, ep.step_s, ep.n_faults
        )
    finally:
        if not kept:
            env.close()


class EnvCache:
    """The symbolic env of the last ``rl:PATH`` episode, by its options, owned by its caller.

    A sweep's episodes differ in scene and seed only, and every reset reseeds the env, so
    one env serves them all (making it and deriving each scene anew cost more than the
    episode). `get` returns the kept env for equal options and closes it on new ones; the
    owner calls `close` (or uses it as a context manager) when done."""

    def __init__(self) -> None:
        self._key: str | None = None
        self._env: Any = None

    def get(self, env_id: str, grounding: str, options: dict[str, Any]) -> Any:
        """The env of `env_id` in `grounding` with `options`: the kept one if equal, else new."""
        import gymnasium as gym

        key = repr((env_id, grounding, sorted(options.items())))
        if key != self._key:
            self.close()
            self._env = gym.make(env_id, grounding=grounding, **options)
            self._key = key
        return self._env

    def close(self) -> None:
        """Close the kept env, if any."""
        if self._env is not None:
            self._env.close()
        self._key, self._env = None, None

    def __enter__(self) -> EnvCache:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _terminal_reason(info: dict[str, Any], steps: int) -> str:
    """Why an episode ended without the goal: a perceived anomaly (physics) or a dead end."""
    anomalies = {k: v for k, v in dict(info.get("anomalies") or {}).items() if v}
    if anomalies:
        shown = "; ".join(f"{k}: {v}" for k, v in sorted(anomalies.items()))
        return f"anomaly after {steps} steps: {shown}"
    return f"dead end: no applicable action after {steps} steps"
