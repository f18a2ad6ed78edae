"""What the agent observes and is rewarded for: spaces, reward, termination (dm_control's Task).

Why separate from the env: both groundings share these definitions; only where the numbers
come from differs (the symbolic state or the physics backend).

Reward: `GOAL_REWARD` on the step that reaches the goal. With shaping, additionally
`PROGRESS_BONUS` per unit of progress towards the goal newly made and `-FAILURE_PENALTY` per
failed action. Progress (`progress`) is the number of the goal's literals that hold (in the
symbolic state; in physics in the measured one), or for the paper's tower goal the number of
objects standing on its tower (as before goals were data: the tower's results stand). It is
counted against the episode's best so far, so undoing a step and redoing it earns nothing.
"""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from utamp_gym.tasks.goal import Goal

GOAL_REWARD = 1.0
PROGRESS_BONUS = 0.1
TOWER_BONUS = PROGRESS_BONUS  # its name while the tower was the only goal
TOWER = "tower"  # the paper's goal template: progress is its tower's height
FAILURE_PENALTY = 0.01
POSE_SIZE = 7  # x, y, z, qw, qx, qy, qz
N_JOINTS = 9  # 7 arm joints + 2 fingers
POSITION_LIMIT = 5.0  # m: |x|, |y|, |z| bound of object positions (the table is about 1 m)


def home_joints() -> np.ndarray:
    """The Panda's ready pose with the fingers open: the robot obs in symbolic grounding."""
    # lazy: utamp_gym.robot.kinematics imports pinocchio
    from utamp_gym.robot.kinematics import HOME_Q  # pinocchio: import only when needed

    return np.array([*HOME_Q, 0.04, 0.04], np.float32)


def observation_space(
    n_fluents: int, n_objects: int, image_size: tuple[int, int] | None
) -> spaces.Dict:
    """The observation `Dict` (see `UTampKitchenEnv` for the meaning of each entry)."""
    pose_low = np.tile(np.array([-POSITION_LIMIT] * 3 + [-1.0] * 4, np.float32), (n_objects, 1))
    entries: dict[str, spaces.Space] = {
        "symbolic": spaces.MultiBinary(n_fluents),
        "object_poses": spaces.Box(pose_low, -pose_low, dtype=np.float32),
        "present": spaces.MultiBinary(n_objects),
        "robot": spaces.Box(-2 * math.pi, 2 * math.pi, (N_JOINTS,), np.float32),
    }
    if image_size is not None:
        entries["image"] = spaces.Box(0, 255, (*image_size, 3), np.uint8)
    return spaces.Dict(entries)


def progress(goal: Goal, held: int, tower_height: int) -> int:
    """Reward shaping's progress towards `goal`: its literals that hold (`held`), or for the
    paper's tower the objects standing on it (`tower_height`)."""
    return tower_height if goal.template == TOWER else held


class KitchenTask:
    """Reward and termination of one episode."""

    def __init__(self, *, shaping: bool, terminate_on_failure: bool) -> None:
        self.shaping = shaping
        self.terminate_on_failure = terminate_on_failure
        self._best = 0

    def initialize_episode(self, progress: int) -> None:
        self._best = progress

    def outcome(self, *, goal: bool, failed: bool, progress: int) -> tuple[float, bool]:
        """(reward, terminated) of a step; `progress` as `progress` measures it."""
        reward = GOAL_REWARD if goal else 0.0
        if self.shaping:
            if failed:
                reward -= FAILURE_PENALTY
            if progress > self._best:
                reward += PROGRESS_BONUS * (progress - self._best)
        self._best = max(self._best, progress)
        return reward, goal or (failed and self.terminate_on_failure)
