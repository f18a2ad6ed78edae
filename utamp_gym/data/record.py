"""`record_demos`: record N planner episodes of a suite on an executor and write one dataset.

One executor task per episode (`utamp_gym.distributed`: local worker processes or Ray tasks,
as the evaluation sweeps); the episodes are written in their index order, so the dataset does
not depend on the executor or on completion order. An episode whose task failed is left out
and named in the result; so is one whose scene's goal the planner proved unreachable (the
procedural splits hold such scenes on purpose), apart, as `DemoResult.unsolvable`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from utamp_gym import suites
from utamp_gym.data import lowlevel, macro
from utamp_gym.data.minari_io import Episode, write_dataset
from utamp_gym.distributed import LocalExecutor
from utamp_gym.env.registry import env_definitions
from utamp_gym.errors import UnknownNameError, UtampError
from utamp_gym.rl.harness import suite_options

if TYPE_CHECKING:
    from utamp_gym.distributed import Executor

TRACKS = ("macro", "low-level")


@dataclass
class DemoResult:
    """What `record_demos` wrote."""

    dataset_id: str
    path: Path
    episodes: int
    steps: int
    successes: int
    failed: dict[int, str] = field(default_factory=dict)
    #: episodes left out because the planner proved their goal unreachable from the start
    unsolvable: dict[int, str] = field(default_factory=dict)


def proved_unsolvable(reason: str) -> bool:
    """Whether a planner error says the goal was *proved* unreachable (relaxed reachability,
    the translator, or Fast Downward's exhausted complete search), not a time-out or an
    incomplete search."""
    return "proved unsolvable" in reason or "search space exhausted: task unsolvable" in reason


def suite_env(suite: str) -> tuple[str, dict[str, Any]]:
    """The registered env id of a suite, and the options that select it (a suite without an
    id of its own runs in ``UTampKitchen-v0`` with its suite and object rows)."""
    every = getattr(suites, "ALL_SUITES", suites.SUITES)  # with the procedural splits
    if suite not in every:
        raise UnknownNameError("suite", suite, every)
    for d in env_definitions():
        if d.kwargs.get("suite") == suite:
            return d.id, {}
        split = d.kwargs.get("split")
        if split is not None and _split_suite(split) == suite:  # a procedural split's env
            return d.id, {"split": split}
    version = suite.split("/", 1)[0]
    if "/" in suite:  # another split of a procedural env: the env of that version's splits
        for d in env_definitions():
            split = d.kwargs.get("split")
            if split is not None and _split_suite(split).split("/", 1)[0] == version:
                return d.id, {"split": suite if "/" in split else suite.rsplit("/", 1)[1]}
    return "UTampKitchen-v0", suite_options(suites.suite_scenes(suite)[0].name)


def _split_suite(split: str) -> str:
    """The suite of an env's ``split`` option ("train": procedural-v1's; or a full name)."""
    return split if "/" in split else f"{suites.PROCEDURAL}/{split}"


def dataset_id(suite: str, track: str, method: str) -> str:
    """``utamp/<suite>-<track>-<method>-v0`` (Minari's namespace/name-version syntax)."""
    return f"utamp/{suite.replace('/', '-')}-{track}-{method}-v0"


def record_demos(
    suite: str,
    episodes: int,
    out: str | Path,
    *,
    track: str = "macro",
    seed: int = 0,
    method: str = "utamp2-gt",
    env_options: Mapping[str, Any] | None = None,
    image_size: tuple[int, int] | None = None,
    executor: Executor | None = None,
) -> DemoResult:
    """Record `episodes` planner episodes of `suite` (reset seeds ``seed ..``) on `executor`
    (default: in this process) and write them as one Minari dataset under `out`."""
    if track not in TRACKS:
        raise UnknownNameError("track", track, TRACKS)
    if episodes < 1:
        raise UtampError(f"--episodes must be at least 1, got {episodes}")
    env_id, options = suite_env(suite)
    options = {**options, **(env_options or {})}
    tasks: list[Any]
    if track == "macro":
        tasks = macro.tasks(env_id, episodes, seed=seed, method=method, env_options=options)
        fn: Any = macro.record_episode
    else:
        size = image_size or lowlevel.DEFAULT_IMAGE_SIZE
        tasks = [
            lowlevel.LowLevelTask(
                lowlevel.scene_of(env_id, seed + i, options), i, seed + i, method, size
            )
            for i in range(episodes)
        ]
        fn = lowlevel.record_episode
    done: dict[int, Episode] = {}
    failed: dict[int, str] = {}
    unsolvable: dict[int, str] = {}

    def record(item: tuple[int, Episode | str]) -> None:
        index, result = item
        if isinstance(result, str):  # the task raised (low-level: no plan to record)
            (unsolvable if proved_unsolvable(result) else failed)[index] = result
        else:
            done[index] = result

    (executor or LocalExecutor(0)).run(
        _Task(fn), tasks, record, lambda task, reason: (task.index, reason)
    )
    kept = [done[i] for i in sorted(done) if done[i].actions]
    for i in sorted(done):
        if not done[i].actions:
            reason = str(done[i].metadata.get("planner_error") or "no step recorded")
            (unsolvable if proved_unsolvable(reason) else failed)[i] = reason
    if not kept:
        raise UtampError(f"no episode of {suite} could be recorded: {failed or unsolvable}")
    name = dataset_id(suite, track, method)
    if track == "macro":
        env = macro.make_env(env_id, options)
        try:
            path = write_dataset(
                out, name, kept, env=env, algorithm_name=f"planner policy ({method})",
                description=f"{method} planner-policy episodes of the {suite} suite "
                f"({env_id}, {options}), one per reset seed; per-episode metadata holds the "
                "scene, its scene file, the seed and the macro actions",
            )  # fmt: skip
        finally:
            env.close()
    else:
        size = image_size or lowlevel.DEFAULT_IMAGE_SIZE
        path = write_dataset(
            out, name, kept, observation_space=lowlevel.observation_space(size),
            action_space=lowlevel.action_space(), algorithm_name=f"planner plan replay ({method})",
            description=f"joint commands at 50 Hz replaying {method} plans of the {suite} suite "
            "through utamp_gym.dm, with scene-camera images and per-step macro-action labels",
        )  # fmt: skip
    return DemoResult(
        name, path, len(kept), sum(len(e.actions) for e in kept),
        sum(bool(e.metadata.get("success")) for e in kept), failed, unsolvable,
    )  # fmt: skip


@dataclass(frozen=True)
class _Task:
    """An executor task: ``(index, episode)`` of one recording function (picklable)."""

    fn: Any

    def __call__(self, task: Any) -> tuple[int, Episode]:
        return task.index, self.fn(task)
