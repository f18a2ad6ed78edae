"""The low-level track: the planner's macro plan as joint commands at control rate, with
scene-camera images and a per-frame macro-action label (the dm_control track, `utamp_gym.dm`).

An episode picks its scene as the macro track does (``reset(seed=s)`` of the suite's env),
plans it with the planner (Fast Downward, open loop), records the servo commands the physics
executor sends for the plan (`utamp_gym.dm.record_plan`, no pose noise) and replays them, one
row per 50 Hz control step, through ``utamp_gym.dm.load(scene, seed=s)`` without initial noise
(`utamp_gym.dm.ReplayPolicy`). Each control step keeps the observation (fixed size for every
scene: `observation_space`), the 8 commands, the task's reward, and in the info the label: the
PDDL string of the macro action that sent the commands (``""`` while the last command is held)
and its index in the plan (-1 then).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from utamp_gym.data.macro import make_env
from utamp_gym.data.minari_io import Episode
from utamp_gym.errors import PlanningError
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene.io import scene_to_toml
from utamp_gym.suites import resolve_scene

MAX_OBJECTS = 6  # object_poses rows (scene order), as the objects interface's slots
DEFAULT_IMAGE_SIZE = (96, 96)  # (height, width) of the scene camera
CAMERA = "overview"
HOLD_S = 0.5  # s the last command is held after the plan


@dataclass(frozen=True)
class LowLevelTask:
    """One episode to record (picklable: sent to worker processes or Ray)."""

    scene: str
    index: int
    seed: int
    method: str = "utamp2-gt"
    image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE


def observation_space(image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE) -> Any:
    from gymnasium import spaces

    box = lambda *shape: spaces.Box(-np.inf, np.inf, shape, np.float64)  # noqa: E731
    return spaces.Dict({
        "arm_qpos": box(7), "arm_qvel": box(7), "gripper_gap": box(1),
        "object_poses": box(MAX_OBJECTS, 7), "present": spaces.MultiBinary(MAX_OBJECTS),
        "tower_height": box(1), "image": spaces.Box(0, 255, (*image_size, 3), np.uint8),
    })  # fmt: skip


def action_space() -> Any:
    """7 joint-position targets (rad) and the gripper gap (m), as `StackTask.action_spec`."""
    from gymnasium import spaces

    # lazy: utamp_gym.dm.physics imports dm_control, dm_env, mujoco, ompl, pinocchio
    from utamp_gym.dm.physics import KitchenPhysics

    physics = KitchenPhysics.build(resolve_scene("kitchen-demo"))
    low, high = physics.model.actuator_ctrlrange.T
    return spaces.Box(low.astype(np.float64), high.astype(np.float64), (len(low),), np.float64)


def _observation(time_step: Any, physics: Any, size: tuple[int, int]) -> dict[str, np.ndarray]:
    o = time_step.observation
    poses = np.zeros((MAX_OBJECTS, 7))
    n = len(o["object_poses"])
    poses[:n] = o["object_poses"]
    present = np.zeros(MAX_OBJECTS, np.int8)
    present[:n] = 1
    image = physics.render(height=size[0], width=size[1], camera_id=CAMERA)
    return {
        "arm_qpos": np.asarray(o["arm_qpos"], np.float64),
        "arm_qvel": np.asarray(o["arm_qvel"], np.float64),
        "gripper_gap": np.asarray(o["gripper_gap"], np.float64),
        "object_poses": poses, "present": present,
        "tower_height": np.asarray(o["tower_height"], np.float64),
        "image": np.asarray(image, np.uint8),
    }  # fmt: skip


def scene_of(env_id: str, seed: int, options: Mapping[str, Any] | None = None) -> str:
    """The scene the macro env's ``reset(seed=seed)`` picks (the two tracks share scenes);
    `options` select the scenes (a suite, a procedural ``split``)."""
    env = make_env(env_id, {**(options or {}), "grounding": "symbolic"})
    try:
        env.reset(seed=seed)
        return str(env.unwrapped.scene.name)
    finally:
        env.close()


def load_env(scene: str, seed: int, duration_s: float) -> Any:
    """The dm_control environment an episode is recorded (and replayed) in: no initial noise."""
    # lazy: utamp_gym.dm imports dm_control, dm_env, mujoco, ompl, pinocchio
    from utamp_gym import dm

    return dm.load(scene=scene, seed=seed, pos_noise=0.0, yaw_noise_deg=0.0,
                   time_limit=duration_s + 2.0)  # fmt: skip


def record_episode(task: LowLevelTask) -> Episode:
    """Plan, record the joint commands and replay them at control rate, keeping every step."""
    # lazy: utamp_gym.dm imports dm_control, dm_env, mujoco, ompl, pinocchio
    from utamp_gym.dm import CONTROL_TIMESTEP, ReplayPolicy, record_plan

    scene = resolve_scene(task.scene)
    outcome = plan_scene(scene, task.method, seed=task.seed)
    if not outcome.solved:
        raise PlanningError(f"{scene.name}: no plan to record ({outcome.reason})")
    trajectory = record_plan(scene, outcome.plan, seed=task.seed, hold_s=HOLD_S)
    policy = ReplayPolicy(trajectory, CONTROL_TIMESTEP)
    steps = policy.trajectory.steps
    assert steps is not None
    env = load_env(task.scene, task.seed, policy.trajectory.duration)
    time_step = env.reset()
    physics = env.physics
    ep = Episode(seed=task.seed, observations=[_observation(time_step, physics, task.image_size)],
                 infos=[{"macro_action": "", "macro_step": np.int64(-1)}])  # fmt: skip
    for k in range(policy.n_steps):
        action = policy(time_step)
        time_step = env.step(action)
        label = int(steps[k])
        ep.observations.append(_observation(time_step, physics, task.image_size))
        ep.actions.append(np.asarray(action, np.float64))
        ep.rewards.append(float(time_step.reward or 0.0))
        last = time_step.last()
        ep.terminations.append(bool(last and time_step.discount == 0.0))
        ep.truncations.append(bool(last and time_step.discount != 0.0))
        ep.infos.append({"macro_action": outcome.plan[label] if label >= 0 else "",
                         "macro_step": np.int64(label)})  # fmt: skip
        if last:
            break
    ep.metadata = {
        "index": task.index,
        "scene": scene.name,
        "scene_file": scene_to_toml(scene),
        "seed": task.seed,
        "method": task.method,
        "macro_actions": list(outcome.plan),
        "control_timestep": CONTROL_TIMESTEP,
        "success": bool(env.task.goal_reached(physics)),
        "duration_s": policy.trajectory.duration,
    }
    return ep


def replay(scene: str, seed: int, actions: np.ndarray, duration_s: float) -> dict[str, Any]:
    """The last dm_control observation after `actions` from the episode's start."""
    env = load_env(scene, seed, duration_s)
    time_step = env.reset()
    for a in actions:
        time_step = env.step(np.asarray(a))
    return dict(time_step.observation)
