"""`train`: MaskablePPO, PPO or DQN on a kitchen env, with evaluation, checkpoints and a curve.

Why three algorithms: MaskablePPO is the baseline (it samples only applicable actions, from
`action_masks()`); PPO and DQN learn the same task without masks, which measures what the
masks are worth. All three get the same reward, ``reward_shaping=True`` (+1 goal, +0.1 per
new tower object, −0.01 per failed action) without ``terminate_on_failure``: an unmasked
agent then pays for invalid actions but keeps exploring until the time limit, whereas ending
the episode at the first of them (2–5 of the ~200 actions apply) would leave it almost no
chance to reach a rewarded state. Evaluation uses the deterministic policy with masks for
every algorithm (PPO/DQN pick the best applicable action; ``eval_masks=False`` turns
that off) on a fixed cycle of the env's scenes.

Mask modes (``masks``, the env option): "affordances" shows the agent the U-TAMP-2
precondition under ground-truth affordances (the planner's knowledge); "geometric" only the
object-centric preconditions, with the symbolic outcome model rejecting what the ground truth
forbids; "none" every action of the scene. MaskablePPO trains with the mode's masks; PPO and
DQN never see masks in training (evaluation applies the mode's mask unless ``eval_masks`` is
False).

Outputs in `out`: ``model.zip`` (final), ``checkpoints/step_<n>.zip`` (at every
evaluation), ``learning_curve.png`` and ``train.json`` (config, steps, wall times, curve).
Every zip carries its `ModelMeta` (env id, masks, observation keys, space sizes), so
``utamp eval --methods rl:PATH`` rebuilds its env. `train_seeds` runs `train` once per seed
(``out/seed_<s>/``; one call per seed, so an executor may run them in parallel) and
`aggregate_seeds` writes ``aggregate.json`` and ``learning_curves.png`` (mean and min-max
band across seeds).
"""

from __future__ import annotations

import functools
import json
import platform
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from utamp_gym.errors import UtampError
from utamp_gym.rl.envs import (
    DEFAULT_OBS_KEYS,
    EVAL_SEED_OFFSET,
    OBJECT_OBS_KEYS,
    default_interface,
    make_env,
    make_vec_env,
    n_fluents,
)
from utamp_gym.rl.policy import ALGOS, algo_class
from utamp_gym.rl.saved import ModelMeta, write_meta

if TYPE_CHECKING:
    from utamp_gym.distributed import Executor

GROUNDINGS = ("symbolic", "physics")
#: PPO epochs per rollout of the slot policy: the update is most of its training time, and 4
#: epochs learn as much per env step as 10 did (benchmarks/train_speed_learning.py)
OBJECTS_EPOCHS = 4
#: what `train` trains: the RL algorithms, and behaviour cloning from demonstrations
TRAIN_ALGOS = (*ALGOS, "bc")


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a run (written to ``train.json``).

    `num_objects` None trains on every scene of the suite (2–5 objects); `hyperparams`
    overrides `default_hyperparams`; `obs_keys` are the observation entries the agent sees;
    `interface` is the env option (``objects``: MaskablePPO with `utamp_gym.rl.slots.SlotPolicy`
    over all of the objects interface's entries; ``""``: the env's own, `default_interface`);
    `init_from` is a model zip whose policy weights the run starts from (fine-tuning a
    behaviour-cloned policy).
    """

    env_id: str = "UTampKitchen-v0"
    algo: str = "maskable-ppo"
    grounding: str = "symbolic"
    num_objects: int | None = None
    masks: str = "affordances"
    steps: int = 200_000
    n_envs: int = 8
    seed: int = 0
    eval_every: int = 10_000
    eval_episodes: int = 60
    eval_masks: bool = True
    target_success: float = 0.9
    stop_at_target: bool = False
    reward_shaping: bool = True
    terminate_on_failure: bool = False
    obs_keys: tuple[str, ...] = DEFAULT_OBS_KEYS
    hyperparams: dict[str, Any] = field(default_factory=dict)
    interface: str = ""
    init_from: str = ""
    demos: str = ""

    def __post_init__(self) -> None:
        from utamp_gym.env.options import INTERFACES

        if not self.interface:
            object.__setattr__(self, "interface", default_interface(self.env_id, self.algo))

        if self.interface not in INTERFACES:
            raise ValueError(f"unknown interface {self.interface!r}; valid: grounded, objects")
        if self.interface == "objects":
            if self.algo not in ("maskable-ppo", "bc"):
                raise ValueError(
                    f"interface 'objects' trains maskable-ppo with the slot policy "
                    f"(utamp_gym.rl.slots), not {self.algo!r}"
                )
            if tuple(self.obs_keys) == DEFAULT_OBS_KEYS:  # the objects interface's entries
                object.__setattr__(self, "obs_keys", OBJECT_OBS_KEYS)
        if self.algo not in TRAIN_ALGOS:
            raise ValueError(f"unknown algo {self.algo!r}; valid: {', '.join(TRAIN_ALGOS)}")
        if (self.algo == "bc") != bool(self.demos):
            raise ValueError("algo 'bc' (and only it) needs demos: a `utamp demos` dataset folder")
        if self.algo == "bc" and self.interface != "objects":
            raise ValueError("behaviour cloning trains the slot policy: use interface 'objects'")
        if self.grounding not in GROUNDINGS:
            raise ValueError(f"unknown grounding {self.grounding!r}; valid: symbolic, physics")
        from utamp_gym.env.options import MASKS

        if self.masks not in MASKS:
            raise ValueError(f"unknown masks {self.masks!r}; valid: {', '.join(MASKS)}")
        for name in ("steps", "n_envs", "eval_every", "eval_episodes"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)}")


@dataclass(frozen=True)
class TrainResult:
    """What `train` produced: paths, steps, times and the evaluation curve.

    `wall_time_s` is the whole call; `train_time_s` leaves out the evaluations and
    checkpoints, as do the curve's times and `time_to_target_s` (training time until the
    first evaluation with success ≥ `TrainConfig.target_success`).
    """

    out: Path
    model_path: Path
    steps: int
    wall_time_s: float
    train_time_s: float
    final_success: float
    steps_to_target: int | None
    time_to_target_s: float | None
    curve: list[dict[str, Any]]


def default_hyperparams(algo: str, n_envs: int, interface: str = "grounded") -> dict[str, Any]:
    """The algorithm settings used unless `TrainConfig.hyperparams` overrides them (the slot
    policy of the objects interface at `utamp_gym.rl.slots.train_policy_kwargs`)."""
    from utamp_gym.rl.slots import train_policy_kwargs

    objects = interface == "objects"
    net: dict[str, Any] = train_policy_kwargs() if objects else {"net_arch": [128, 128]}
    if algo == "dqn":
        return {
            "learning_rate": 1e-4, "buffer_size": 100_000, "learning_starts": 1_000,
            "batch_size": 64, "gamma": 0.99, "train_freq": 4, "target_update_interval": 1_000,
            "exploration_fraction": 0.3, "exploration_final_eps": 0.05, "policy_kwargs": net,
        }  # fmt: skip
    return {
        "learning_rate": 3e-4, "n_steps": max(16, 1024 // n_envs), "batch_size": 256,
        "n_epochs": OBJECTS_EPOCHS if objects else 10, "gamma": 0.99, "gae_lambda": 0.95,
        "ent_coef": 0.01, "policy_kwargs": net,
    }  # fmt: skip


def model_meta(config: TrainConfig, env: Any) -> ModelMeta:
    """The `ModelMeta` of a run, read from its (unfiltered) evaluation env."""
    kitchen = env.unwrapped
    options: dict[str, Any] = {"masks": config.masks, "interface": config.interface}
    return ModelMeta(
        env_id=config.env_id,
        suite=str(kitchen.options.suite),
        algo="maskable-ppo" if config.algo == "bc" else config.algo,  # the model's class
        obs_keys=tuple(config.obs_keys),
        n_actions=int(env.action_space.n),
        n_fluents=n_fluents(env),
        env_options=options,
        trained_grounding=config.grounding,
    )


def save_model(model: Any, path: str | Path, meta: ModelMeta) -> None:
    """``model.save(path)`` plus the `ModelMeta` inside the zip."""
    model.save(path)
    write_meta(path, meta)


def eval_episodes_of(config: TrainConfig) -> list[tuple[str, int]]:
    """The (scene, seed) pairs of every evaluation: the env's scenes in turn."""
    # every observation entry: the env's default interface may have no ``symbolic`` entry;
    # the run's masks, so that the env reuses the run's (cached) action universe
    env = make_env(config.env_id, grounding="symbolic", num_objects=config.num_objects,
                   obs_keys=None, masks=config.masks)  # fmt: skip
    names = [s.name for s in env.unwrapped.scenes]  # type: ignore[attr-defined]
    env.close()
    base = config.seed + EVAL_SEED_OFFSET
    return [(names[i % len(names)], base + i) for i in range(config.eval_episodes)]


def train(
    env_id: str = "UTampKitchen-v0",
    algo: str = "maskable-ppo",
    grounding: str = "symbolic",
    num_objects: int | None = None,
    steps: int = 200_000,
    n_envs: int = 8,
    seed: int = 0,
    out: str | Path = "runs/rl",
    eval_every: int = 10_000,
    eval_episodes: int = 60,
    *,
    progress: bool = True,
    verbose: int = 0,
    **options: Any,
) -> TrainResult:
    """Train `algo` on `env_id` and write the outputs to `out` (see the module docstring).

    `options` are the other `TrainConfig` fields (``masks``, ``eval_masks``, ``target_success``,
    ``stop_at_target``, ``reward_shaping``, ``terminate_on_failure``, ``obs_keys``,
    ``hyperparams``). Physics grounding trains in ``SubprocVecEnv`` workers.
    """
    import torch
    from stable_baselines3.common.logger import HumanOutputFormat, Logger

    from utamp_gym.rl.callbacks import PeriodicEval, ProgressBar, plot_learning_curve
    from utamp_gym.rl.policies import POLICY_CLASSES

    config = TrainConfig(
        env_id=env_id, algo=algo, grounding=grounding, num_objects=num_objects, steps=steps,
        n_envs=n_envs, seed=seed, eval_every=eval_every, eval_episodes=eval_episodes,
        **options,
    )  # fmt: skip
    torch.set_num_threads(1)
    out = Path(out)
    (out / "checkpoints").mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    if algo == "bc":
        from utamp_gym.rl.bc import train_bc

        result, hyper = train_bc(config, out)
        (out / "train.json").write_text(json.dumps(_report(config, hyper, result), indent=2) + "\n")
        return result

    env_kw: dict[str, Any] = {
        "grounding": grounding,
        "num_objects": num_objects,
        "masks": config.masks,
        "interface": config.interface,
    }
    vec = make_vec_env(
        env_id, n_envs, seed=seed, subproc=grounding == "physics", obs_keys=config.obs_keys,
        reward_shaping=config.reward_shaping, terminate_on_failure=config.terminate_on_failure,
        **env_kw,
    )  # fmt: skip
    eval_env = make_env(env_id, obs_keys=None, **env_kw)
    meta = model_meta(config, eval_env)
    save = functools.partial(save_model, meta=meta)
    hyper = {**default_hyperparams(algo, n_envs, config.interface), **config.hyperparams}
    start_from = None
    if config.init_from:  # fine-tuning: the saved policy's network, then its weights
        start_from = algo_class(algo).load(config.init_from, device="cpu")
        if "policy_kwargs" not in config.hyperparams:
            hyper["policy_kwargs"] = dict(start_from.policy_kwargs)
    policy_class = POLICY_CLASSES[algo]
    if config.interface == "objects":
        from utamp_gym.rl.slots import SlotPolicy

        policy_class = SlotPolicy
    model = algo_class(algo)(policy_class, vec, seed=seed, verbose=verbose, **hyper)
    # given no logger, SB3 makes an empty /tmp/SB3-<time> folder per run: log to stdout only
    model.set_logger(Logger(None, [HumanOutputFormat(sys.stdout)] if verbose else []))
    if start_from is not None:  # fine-tuning: start from a saved policy (e.g. behaviour cloning)
        model.policy.load_state_dict(start_from.policy.state_dict())
    evaluator = PeriodicEval(
        eval_env, eval_episodes_of(config), out, eval_every, save=save,
        masks=config.eval_masks, stop_at=config.target_success if config.stop_at_target else None,
    )  # fmt: skip
    callbacks: list[Any] = [evaluator]
    if progress:
        callbacks.append(ProgressBar(steps, evaluator))
    try:
        model.learn(total_timesteps=steps, callback=callbacks)
    finally:
        vec.close()
        eval_env.close()
    model_path = out / "model.zip"
    save(model, model_path)
    wall = time.perf_counter() - start

    points = evaluator.points
    hit = next((p for p in points if p.success_rate >= config.target_success), None)
    result = TrainResult(
        out=out,
        model_path=model_path,
        steps=int(model.num_timesteps),
        wall_time_s=round(wall, 3),
        train_time_s=round(wall - evaluator.eval_time_s, 3),
        final_success=points[-1].success_rate,
        steps_to_target=hit.steps if hit else None,
        time_to_target_s=hit.wall_time_s if hit else None,
        curve=[p.to_json() for p in points],
    )
    title = (
        f"{algo}, masks {config.masks}, on {env_id} ({grounding}, {num_objects or '2-5'} "
        f"objects, seed {seed})"
    )
    plot_learning_curve(points, out / "learning_curve.png", title, config.target_success)
    (out / "train.json").write_text(json.dumps(_report(config, hyper, result), indent=2) + "\n")
    return result


def _report(config: TrainConfig, hyper: dict[str, Any], result: TrainResult) -> dict[str, Any]:
    import sb3_contrib
    import stable_baselines3
    import torch

    data = asdict(result)
    data["out"], data["model_path"] = str(result.out), str(result.model_path)
    return {
        "config": {**asdict(config), "obs_keys": list(config.obs_keys)},
        "hyperparams": hyper,
        **data,
        "versions": {
            "python": platform.python_version(),
            "stable_baselines3": stable_baselines3.__version__,
            "sb3_contrib": sb3_contrib.__version__,
            "torch": torch.__version__,
        },
    }


def seed_dir(out: str | Path, seed: int) -> Path:
    """Where `train_seeds` puts the run of one seed."""
    return Path(out) / f"seed_{seed}"


def finished_run(out: str | Path, config: TrainConfig) -> TrainResult | None:
    """The result of a finished run of exactly `config` in `out` (its ``train.json`` and
    ``model.zip``), or None."""
    out = Path(out)
    report_path = out / "train.json"
    if not report_path.is_file() or not (out / "model.zip").is_file():
        return None
    report = json.loads(report_path.read_text())
    want = {**asdict(config), "obs_keys": list(config.obs_keys)}
    if report.get("config") != want:
        return None
    names = {f.name for f in fields(TrainResult)}
    data = {k: v for k, v in report.items() if k in names}
    return TrainResult(**{**data, "out": out, "model_path": out / "model.zip"})


def train_seed(seed: int, out: str | Path, **kwargs: Any) -> TrainResult:
    """One seed of `train_seeds`: `train` into `seed_dir`, or its finished run if there is
    one with the same configuration (so an interrupted or split job resumes)."""
    options = {k: v for k, v in kwargs.items() if k not in ("progress", "verbose")}
    config = TrainConfig(seed=seed, **options)
    done = finished_run(seed_dir(out, seed), config)
    return done if done is not None else train(seed=seed, out=seed_dir(out, seed), **kwargs)


def train_seeds(
    seeds: int = 1,
    *,
    out: str | Path = "runs/rl",
    seed: int = 0,
    executor: Executor | None = None,
    **kwargs: Any,
) -> dict[str, Any]:
    """`seeds` independent runs (seeds ``seed`` to ``seed + seeds - 1``), one `train_seed` call
    each, then `aggregate_seeds`; `kwargs` are `train`'s. Returns the aggregate.

    With an `executor` (`utamp_gym.distributed`: local worker processes or Ray tasks) the
    seeds train in parallel; without one, one after another in this process. If a seed
    fails, the others still finish (and are reused by the next call) and `UtampError`
    names the failed seeds with their reasons.
    """
    if seeds < 1:
        raise ValueError(f"seeds must be a positive integer, got {seeds}")
    todo = list(range(seed, seed + seeds))
    if executor is None:
        results = [train_seed(s, out, **kwargs) for s in todo]
    else:
        done: dict[int, TrainResult] = {}
        failures: dict[int, str] = {}

        def record(item: tuple[int, TrainResult | str]) -> None:
            s, result = item
            if isinstance(result, str):
                failures[s] = result
            else:
                done[s] = result

        executor.run(
            functools.partial(_train_seed_task, out=str(out), kwargs=kwargs),
            todo,
            record,
            lambda s, reason: (s, reason),
        )
        if failures:
            listed = "; ".join(f"seed {s}: {r}" for s, r in sorted(failures.items()))
            raise UtampError(
                f"{len(failures)} of {seeds} training runs failed ({listed}); the finished "
                "seeds are kept and reused when the same command runs again"
            )
        results = [done[s] for s in todo]
    return aggregate_seeds(results, out)


def _train_seed_task(seed: int, *, out: str, kwargs: dict[str, Any]) -> tuple[int, TrainResult]:
    """One executor task of `train_seeds` (a module-level function, so it pickles)."""
    return seed, train_seed(seed, out, **kwargs)


def _mean_std(xs: Sequence[float]) -> dict[str, float | None]:
    if not xs:
        return {"mean": None, "std": None}
    return {"mean": statistics.fmean(xs), "std": statistics.stdev(xs) if len(xs) > 1 else 0.0}


def aggregate_seeds(results: Sequence[TrainResult], out: str | Path) -> dict[str, Any]:
    """Write ``aggregate.json`` and ``learning_curves.png`` (mean and min-max band) for the
    runs of one configuration (read from each run's ``train.json``); returns the aggregate.

    Steps and training time to the target are averaged over the seeds that reached it
    (`reached` of `seeds`); final success over all seeds.
    """
    from utamp_gym.rl.callbacks import plot_learning_curves

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    reports = [json.loads((r.out / "train.json").read_text()) for r in results]
    config = dict(reports[0]["config"])
    config.pop("seed")
    hit = [r for r in results if r.steps_to_target is not None]
    aggregate = {
        "config": config,
        "seeds": [rep["config"]["seed"] for rep in reports],
        "runs": [str(r.out) for r in results],
        "target_success": config["target_success"],
        "reached": len(hit),
        "steps_to_target": _mean_std([float(r.steps_to_target or 0) for r in hit]),
        "time_to_target_s": _mean_std([float(r.time_to_target_s or 0.0) for r in hit]),
        "final_success": _mean_std([r.final_success for r in results]),
        "best_success": _mean_std([max(p["success_rate"] for p in r.curve) for r in results]),
        "train_time_s": _mean_std([r.train_time_s for r in results]),
        "wall_time_s": _mean_std([r.wall_time_s for r in results]),
        "per_seed": [
            {
                "seed": rep["config"]["seed"],
                "steps": r.steps,
                "final_success": r.final_success,
                "steps_to_target": r.steps_to_target,
                "time_to_target_s": r.time_to_target_s,
                "train_time_s": r.train_time_s,
            }
            for rep, r in zip(reports, results, strict=True)
        ],
    }
    label = f"{config['algo']}, masks {config['masks']}"
    title = (
        f"{label} on {config['env_id']} ({config['grounding']}, "
        f"{config['num_objects'] or '2-5'} objects, {len(results)} seeds)"
    )
    plot_learning_curves(
        {label: [r.curve for r in results]},
        out / "learning_curves.png",
        title,
        config["target_success"],
    )
    (out / "aggregate.json").write_text(json.dumps(aggregate, indent=2) + "\n")
    return aggregate
