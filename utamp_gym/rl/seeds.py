"""Several seeds of one configuration: `train_seeds` runs `utamp_gym.rl.train.train` once
per seed (``out/seed_<s>/``; one call per seed, so an executor may run them in parallel;
a finished seed is reused, so an interrupted job resumes) and `aggregate_seeds` writes
``aggregate.json`` and ``learning_curves.png`` (mean and min-max band across seeds).
"""

from __future__ import annotations

import functools
import json
import statistics
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from utamp_gym.errors import UtampError
from utamp_gym.rl.callbacks import plot_learning_curves
from utamp_gym.rl.config import TrainConfig, TrainResult
from utamp_gym.rl.runs import finished_run, seed_dir
from utamp_gym.rl.train import train

if TYPE_CHECKING:
    from utamp_gym.distributed import Executor


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
