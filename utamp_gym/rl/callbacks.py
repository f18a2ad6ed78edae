"""Training callbacks: a tqdm progress bar, periodic masked evaluation with checkpoints, and
the learning-curve plot.

Why custom: SB3's own progress bar needs `rich`, and its ``EvalCallback`` neither applies
action masks to PPO/DQN nor cycles over a fixed scene list; here every evaluation plays the
same (scene, seed) episodes with the deterministic masked policy, so points are comparable.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
from stable_baselines3.common.callbacks import BaseCallback

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
    to ``out/checkpoints/step_<n>.zip``. With `stop_at` set, training stops at the first
    evaluation whose success rate reaches it.
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
    ) -> None:
        super().__init__()
        self.env, self.episodes, self.out, self.every = env, episodes, out, max(1, every)
        self.masks, self.stop_at = masks, stop_at
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
    fig.savefig(path)
