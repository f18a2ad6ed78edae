"""Write and read episodes as Minari datasets (HDF5), with per-episode metadata.

Why our own buffers rather than Minari's `DataCollector`: recording runs in worker processes
(one episode per task) and the episodes are joined at the end, and `create_dataset_from_buffers`
needs neither jax nor a live env. Every episode carries metadata in its HDF5 group's attributes
(`episode_metadata`): the scene's name, its scene file (TOML: every type's declared attributes,
so the episode regenerates without this package's suites), the reset seed and how it was
recorded. Datasets live under a folder of the user's choosing: `datasets_root` points Minari
there for the duration of a call (Minari finds datasets through ``MINARI_DATASETS_PATH``).
"""

from __future__ import annotations

import contextlib
import json
import os
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT_VARIABLE = "MINARI_DATASETS_PATH"


@dataclass
class Episode:
    """One recorded episode: ``n`` steps, ``n + 1`` observations and infos (the reset's
    first), and metadata (JSON-able values)."""

    seed: int
    observations: list[Any]
    actions: list[Any] = field(default_factory=list)
    rewards: list[float] = field(default_factory=list)
    terminations: list[bool] = field(default_factory=list)
    truncations: list[bool] = field(default_factory=list)
    infos: list[Mapping[str, Any]] = field(default_factory=list)
    metadata: dict[str, Any] = field(default_factory=dict)


def stack(items: Sequence[Any]) -> Any:
    """Stack a sequence of equal trees (dicts of arrays, numbers, strings) into one tree of
    arrays (strings: a list of strings, which Minari stores as HDF5 strings; a tuple of
    strings, such as ``info["goal"]``'s atoms: each as one JSON list, HDF5 having no ragged
    string arrays)."""
    first = items[0]
    if isinstance(first, Mapping):
        return {k: stack([item[k] for item in items]) for k in first}
    if isinstance(first, str):
        return [str(item) for item in items]
    if isinstance(first, tuple | list) and all(isinstance(x, str) for x in first):
        return [json.dumps(list(item)) for item in items]
    return np.stack([np.asarray(item) for item in items])


@contextlib.contextmanager
def datasets_root(folder: str | Path) -> Iterator[Path]:
    """Minari reads and writes datasets under `folder` inside the block."""
    folder = Path(folder).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    before = os.environ.get(ROOT_VARIABLE)
    os.environ[ROOT_VARIABLE] = str(folder)
    try:
        yield folder
    finally:
        if before is None:
            os.environ.pop(ROOT_VARIABLE, None)
        else:
            os.environ[ROOT_VARIABLE] = before


def write_dataset(
    root: str | Path,
    dataset_id: str,
    episodes: Sequence[Episode],
    *,
    env: Any = None,
    observation_space: Any = None,
    action_space: Any = None,
    algorithm_name: str,
    description: str,
) -> Path:
    """Write `episodes` as the Minari dataset `dataset_id` under `root` (replacing one of the
    same id) and attach each episode's metadata; returns the dataset's folder."""
    import shutil

    import minari
    from minari.data_collector import EpisodeBuffer

    buffers = [
        EpisodeBuffer(
            id=i,
            seed=ep.seed,
            observations=stack(ep.observations),
            actions=np.asarray(ep.actions),
            rewards=list(map(float, ep.rewards)),
            terminations=list(map(bool, ep.terminations)),
            truncations=list(map(bool, ep.truncations)),
            infos=stack(ep.infos) if ep.infos else None,
        )
        for i, ep in enumerate(episodes)
    ]
    with datasets_root(root) as folder:
        target = folder / dataset_id
        if target.exists():
            shutil.rmtree(target)
        with warnings.catch_warnings():  # minari asks for an e-mail and an eval env
            warnings.filterwarnings("ignore", r".* is set to None|env_spec is None", UserWarning)
            dataset = minari.create_dataset_from_buffers(
                dataset_id, buffers, env=env, observation_space=observation_space,
                action_space=action_space, algorithm_name=algorithm_name,
                description=description, author="utamp_gym", code_permalink="utamp_gym.data",
                data_format="hdf5",
            )  # fmt: skip
        dataset.storage.update_episode_metadata(
            [{k: _attr(v) for k, v in ep.metadata.items()} for ep in episodes]
        )
    return target


def _attr(value: Any) -> Any:
    """An HDF5 attribute value: numbers and strings as they are, anything else as JSON."""
    if isinstance(value, str | int | float | bool | np.integer | np.floating):
        return value
    return json.dumps(value, sort_keys=True)


def load_dataset(root: str | Path, dataset_id: str) -> Any:
    """``minari.load_dataset(dataset_id)`` of a dataset under `root`."""
    import minari

    with datasets_root(root):
        return minari.load_dataset(dataset_id)


def episode_metadata(dataset: Any, index: int) -> dict[str, Any]:
    """The metadata `write_dataset` attached to episode `index` (JSON values decoded)."""
    meta = next(iter(dataset.storage.get_episode_metadata([index])))
    out = {}
    for k, v in meta.items():
        if isinstance(v, bytes):
            v = v.decode()
        if isinstance(v, str) and v[:1] in "[{":
            with contextlib.suppress(json.JSONDecodeError):
                v = json.loads(v)
        out[k] = v.item() if isinstance(v, np.generic) else v
    return out
