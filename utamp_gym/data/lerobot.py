"""Convert a Minari dataset of `utamp demos` into a LeRobot dataset (needs `lerobot`).

Why a converter and not a second recorder: `lerobot` (0.4.4) needs torch < 2.11 and pulls a
CUDA build, so it cannot share this project's environment; a user installs utamp-gym and
lerobot in one environment of their own and converts datasets recorded anywhere. Each Minari
step becomes one LeRobot frame: ``observation.state`` (the low-level track's arm joints,
velocities, gripper gap and padded object poses; the macro track's flattened relational
observation), ``observation.images.scene`` (low-level track), ``action`` (the 8 joint commands,
or the macro action's index as one float) and the ``task`` text, the macro action being
executed (its label), so language-conditioned LeRobot policies see what the planner did.

Tested here against a stand-in that checks the calls the converter makes (the frames, their
keys and shapes); not run against `lerobot` itself in this project (see docs/agents.md).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.data.minari_io import episode_metadata, load_dataset
from utamp_gym.errors import UtampError

LEROBOT_HINT = (
    "utamp demos export-lerobot needs the lerobot package (pip install lerobot, in an "
    "environment of its own: lerobot 0.4.4 requires torch < 2.11)"
)
STATE_KEYS = ("arm_qpos", "arm_qvel", "gripper_gap", "object_poses")


def _dataset_class() -> Any:
    try:  # lerobot >= 0.4
        from lerobot.datasets.lerobot_dataset import LeRobotDataset
    except ImportError:
        try:  # lerobot 0.3
            from lerobot.common.datasets.lerobot_dataset import LeRobotDataset
        except ImportError as exc:
            raise UtampError(f"{LEROBOT_HINT} ({exc})") from None
    return LeRobotDataset


def _state(obs: dict[str, np.ndarray], t: int, low_level: bool) -> np.ndarray:
    if low_level:
        return np.concatenate([np.ravel(obs[k][t]) for k in STATE_KEYS]).astype(np.float32)
    return np.concatenate([np.ravel(obs[k][t]) for k in sorted(obs)]).astype(np.float32)


def export_lerobot(
    root: str | Path, dataset_id: str, out: str | Path, *, repo_id: str | None = None,
    fps: int = 50,
) -> int:  # fmt: skip
    """Write the Minari dataset `dataset_id` (under `root`) as a LeRobot dataset in `out`;
    returns the number of frames written."""
    LeRobotDataset = _dataset_class()
    data = load_dataset(root, dataset_id)
    episodes = list(data.iterate_episodes())
    first = episodes[0]
    low_level = "image" in first.observations
    n_state = len(_state(first.observations, 0, low_level))
    features: dict[str, Any] = {
        "observation.state": {"dtype": "float32", "shape": (n_state,), "names": None},
        "action": {"dtype": "float32", "shape": (8,) if low_level else (1,), "names": None},
    }
    if low_level:
        h, w, _ = first.observations["image"][0].shape
        features["observation.images.scene"] = {
            "dtype": "image", "shape": (h, w, 3), "names": ["height", "width", "channel"],
        }  # fmt: skip
    repo = repo_id or dataset_id.replace("/", "_")
    dataset = LeRobotDataset.create(
        repo_id=repo, fps=fps if low_level else 1, features=features, root=Path(out),
        use_videos=False,
    )  # fmt: skip
    frames = 0
    for ep in episodes:
        meta = episode_metadata(data, int(ep.id))
        labels = ep.infos["macro_action" if low_level else "action"]
        for t in range(len(ep.actions)):
            label = labels[t + 1]
            label = label.decode() if isinstance(label, bytes) else str(label)
            frame: dict[str, Any] = {
                "observation.state": _state(ep.observations, t, low_level),
                "action": np.atleast_1d(np.asarray(ep.actions[t], np.float32)),
                "task": label or f"hold ({meta['scene']})",
            }
            if low_level:
                frame["observation.images.scene"] = ep.observations["image"][t]
            dataset.add_frame(frame)
            frames += 1
        dataset.save_episode()
    finalize = getattr(dataset, "finalize", None)
    if callable(finalize):
        finalize()
    return frames
