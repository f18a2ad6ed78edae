"""Training callbacks: a tqdm progress bar, periodic masked evaluation with checkpoints, and
the learning-curve plot.

Why custom: SB3's own progress bar needs `rich`, and its ``EvalCallback`` neither applies
action masks to PPO/DQN nor cycles over a fixed scene list; here every evaluation plays the
same (scene, seed) episodes with the deterministic masked policy, so points are comparable.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
from stable_baselines3.common.callbacks import BaseCallback

from utamp_gym.provenance import png_metadata
from utamp_gym.rl.policy import RLPolicy, run_episodes


@dataclass(frozen=True)
class EvalPoint:
    """One periodic evaluation."""

    steps: int
    wall_time_s: float
    success_rate: float
    mean_episode_steps: float
    invalid_actions: int
    checkpoint: str

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


class ProgressBar(BaseCallback):
    """A tqdm bar over the training steps, showing the last evaluated success rate."""

    def __init__(self, total: int, evaluator: PeriodicEval | None = None) -> None:
        super().__init__()
        self.total, self.evaluator = total, evaluator
        self._bar: Any = None

    def _on_training_start(self) -> None:
        from tqdm.auto import tqdm

        self._bar = tqdm(total=self.total, unit="step", dynamic_ncols=True)

    def _on_step(self) -> bool:
        self._bar.update(self.training_env.num_envs)
        if self.evaluator is not None and self.evaluator.points:
            self._bar.set_postfix(success=f"{self.evaluator.points[-1].success_rate:.2f}")
        return True

    def _on_training_end(self) -> None:
        self._bar.close()


class PeriodicEval(BaseCallback):
    """Every `every` steps (and at the end): evaluate, record an `EvalPoint`, checkpoint.

    `episodes` are (scene, seed) pairs replayed at every evaluation on `env`; checkpoints go
    to ``out/checkpoints/step_<n>.zip``, written by ``save(model, path)`` (default
    ``model.save``). With `stop_at` set, training stops at the first evaluation whose success
    rate reaches it; with `plateau` set, at the first evaluation where the curve has flattened
    (`plateaued`); with `time_limit_s` set, at the first evaluation after that much training
    time (evaluations left out).
    """

    def __init__(
        self,
        env: gym.Env,
        episodes: list[tuple[str, int]],
        out: Path,
        every: int,
        *,
        masks: bool = True,
        stop_at: float | None = None,
        plateau: float | None = None,
        time_limit_s: float | None = None,
        save: Callable[[Any, Path], None] | None = None,
    ) -> None:
        super().__init__()
        self.env, self.episodes, self.out, self.every = env, episodes, out, max(1, every)
        self.save = save
        self.masks, self.stop_at, self.plateau = masks, stop_at, plateau
        self.time_limit_s = time_limit_s
        self.points: list[EvalPoint] = []
        self._start = time.perf_counter()
        self._next = self.every
        self._eval_s = 0.0

    @property
    def eval_time_s(self) -> float:
        """Wall time spent in evaluations and checkpoints (excluded from `EvalPoint` times)."""
        return self._eval_s

    def _on_training_start(self) -> None:
        self._start = time.perf_counter()
        self._next = (self.num_timesteps // self.every + 1) * self.every

    def _on_step(self) -> bool:
        if self.num_timesteps < self._next:
            return True
        self._next = (self.num_timesteps // self.every + 1) * self.every
        point = self.evaluate()
        if self.plateau is not None and plateaued(self.points, self.plateau):
            return False
        if self.time_limit_s is not None and point.wall_time_s >= self.time_limit_s:
            return False
        return self.stop_at is None or point.success_rate < self.stop_at

    def _on_training_end(self) -> None:
        if not self.points or self.points[-1].steps != self.num_timesteps:
            self.evaluate()

    def evaluate(self) -> EvalPoint:
        """Evaluate the current model now, save a checkpoint, and record the point."""
        begin = time.perf_counter()
        train_s = begin - self._start - self._eval_s
        policy = RLPolicy(self.model, masks=self.masks)
        rows = run_episodes(self.env, policy, self.episodes)
        ckpt = self.out / "checkpoints" / f"step_{self.num_timesteps}.zip"
        if self.save is not None:
            self.save(self.model, ckpt)
        else:
            self.model.save(ckpt)
        point = EvalPoint(
            steps=int(self.num_timesteps),
            wall_time_s=round(train_s, 3),
            success_rate=sum(r["success"] for r in rows) / max(1, len(rows)),
            mean_episode_steps=sum(r["steps"] for r in rows) / max(1, len(rows)),
            invalid_actions=sum(r["invalid_actions"] for r in rows),
            checkpoint=str(ckpt.relative_to(self.out)),
        )
        self.points.append(point)
        self._eval_s += time.perf_counter() - begin
        return point


#: `plateaued`: the fewest evaluations a curve needs before it can be called flat
PLATEAU_MIN_POINTS = 10
#: `plateaued`: the share of the curve's steps whose gain is measured
PLATEAU_TAIL = 0.2


def plateaued(points: Sequence[EvalPoint], min_gain: float = 0.02) -> bool:
    """Whether the last `PLATEAU_TAIL` (20 %) of the curve's steps gained less than
    `min_gain` in success: the running mean of three evaluations at the end against the same
    at the last evaluation at or before 80 % of the steps (the mean damps the noise of
    evaluations of a few episodes). Never before `PLATEAU_MIN_POINTS` evaluations."""
    if len(points) < PLATEAU_MIN_POINTS:
        return False
    rates = [p.success_rate for p in points]
    cut = max(i for i, p in enumerate(points) if p.steps <= (1 - PLATEAU_TAIL) * points[-1].steps)

    def smooth(i: int) -> float:
        window = rates[max(0, i - 2) : i + 1]
        return sum(window) / len(window)

    return smooth(len(rates) - 1) - smooth(cut) < min_gain


def plot_learning_curve(
    points: list[EvalPoint], path: Path, title: str, target: float | None = None
) -> None:
    """Success rate against training steps, as a PNG (matplotlib's Agg backend)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot([p.steps for p in points], [p.success_rate for p in points], "o-")
    if target is not None:
        ax.axhline(target, color="grey", linestyle="--", linewidth=1)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("evaluation success rate")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, metadata=png_metadata())  # with the commit and command


def _at(curve: Sequence[Mapping[str, Any]], steps: int) -> float:
    """Success of a curve at `steps`: its last point at or before (a run stopped at its
    target keeps its last value)."""
    before = [p["success_rate"] for p in curve if p["steps"] <= steps]
    return float(before[-1]) if before else 0.0


def plot_learning_curves(
    groups: Mapping[str, Sequence[Sequence[Mapping[str, Any]]]],
    path: Path,
    title: str,
    target: float | None = None,
) -> None:
    """Success against steps for several configurations, each the mean over its seeds with
    a min-max band; `groups` maps a label to one curve (`EvalPoint` dicts) per seed."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.2), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for k, (label, curves) in enumerate(groups.items()):
        grid = sorted({p["steps"] for c in curves for p in c})
        values = [[_at(c, s) for s in grid] for c in curves]
        cols = list(zip(*values, strict=True))
        mean = [sum(v) / len(v) for v in cols]
        color = f"C{k}"
        ax.fill_between(grid, [min(v) for v in cols], [max(v) for v in cols], color=color,
                        alpha=0.2, linewidth=0)  # fmt: skip
        ax.plot(grid, mean, "-", color=color, label=f"{label} ({len(curves)} seeds)")
    if target is not None:
        ax.axhline(target, color="grey", linestyle="--", linewidth=1)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("evaluation success rate")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, metadata=png_metadata())  # with the commit and command
