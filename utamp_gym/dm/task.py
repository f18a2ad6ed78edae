"""`StackTask`: the kitchen task as a `dm_control.rl.control.Task` (low-level control).

**Actions** – 8 continuous values per control step, the commands of the Panda's position
servos: the 7 arm joint-position targets (rad, within the joint limits) and the gripper gap
command (m, 0 = squeeze with the full gripper force .. 0.08 = open). They are held for the
whole control step (``CONTROL_TIMESTEP`` = 0.02 s, 50 Hz: 10 physics steps of 2 ms).

**Observations** – ``arm_qpos`` (7, rad), ``arm_qvel`` (7, rad/s), ``gripper_gap`` (1, m),
``object_poses`` (n objects in scene order, 7: ``[x, y, z, qw, qx, qy, qz]``), ``symbolic``
(int8 0/1 over `atoms`: the perceived fluent atoms of the U-TAMP-2 domain, as in the Gym
envs) and ``tower_height`` (1: objects standing on the tray's tower).

**Goal** – the scene's own goal (`Scene.goal`: procedural-v2 scenes, scene files with
``[goal]``), else the paper's tower on `Scene.tower_base`.

**Reward** – progress towards the goal: the fraction of the goal's literals that hold in the
perceived atoms (`utamp_gym.tasks.success.literals_held`); for the paper's tower (and a goal
of the ``tower`` template) the fraction of the non-base objects perceived in the tower on its
base (`Perception.tower`). Either is 1 exactly at the goal. The episode ends (discount 0) when
the goal holds in the perceived state: the paper's tower, hand empty, every slot but the base's
clear, no object without a symbol; a scene's goal, every literal holds and every object it is
about is perceived (`utamp_gym.tasks.success.check_perception`, as the Gym envs' success).

**Episodes** – the object poses get fresh noise from the task's random state
(`pos_noise` m, `yaw_noise_deg`); the arm starts at its ready pose, fingers open, and the
scene settles (`settle_s`) before the first observation.
"""

from __future__ import annotations

import collections
from collections.abc import Sequence

import numpy as np
from dm_control.rl import control
from dm_env import specs

from utamp_gym.dm.physics import KitchenPhysics
from utamp_gym.perception.abstraction import Perception
from utamp_gym.robot.panda_mjcf import set_home
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.problem import goal_atoms
from utamp_gym.tasks.success import check_perception, literals_held

CONTROL_TIMESTEP = 0.02  # s: 50 Hz control, 10 physics steps of 2 ms
N_ARM = 7


class StackTask(control.Task):
    """Reach a kitchen scene's goal (the paper's: everything in one tower on its base) by
    commanding joints (module doc)."""

    def __init__(
        self,
        scene: Scene,
        atoms: Sequence[str],
        *,
        pos_noise: float = 0.003,
        yaw_noise_deg: float = 2.0,
        settle_s: float = 0.5,
        random: int | np.random.RandomState | None = None,
    ) -> None:
        if pos_noise < 0 or yaw_noise_deg < 0 or settle_s < 0:
            raise ValueError(
                f"need pos_noise, yaw_noise_deg, settle_s >= 0 "
                f"(got {pos_noise}, {yaw_noise_deg}, {settle_s})"
            )
        if not isinstance(random, np.random.RandomState):
            random = np.random.RandomState(random)
        self.random = random  # the task's one source of randomness (dm_control's convention)
        self.scene, self.atoms = scene, tuple(atoms)
        self.pos_noise, self.yaw_noise_deg, self.settle_s = pos_noise, yaw_noise_deg, settle_s
        self._index = {a: i for i, a in enumerate(self.atoms)}
        self.goal = scene.goal  # None: the paper's tower
        self._goal = frozenset(a.lower() for a in goal_atoms(scene))
        self._others = max(1, scene.n_objects - 1)
        self._perception: Perception | None = None
        self._perceived_at = -1.0

    # ------------------------------------------------------------------ episode
    def initialize_episode(self, physics: KitchenPhysics) -> None:
        """Fresh object noise from `random`, the arm at its ready pose, then settle."""
        rng = np.random.default_rng(self.random.randint(0, 2**32, size=4))
        model, data = physics.model.ptr, physics.data.ptr
        world = physics.world
        data.qpos[:] = world.initial_qpos(
            rng, pos_noise=self.pos_noise, yaw_noise_deg=self.yaw_noise_deg
        )
        data.qvel[:] = 0.0
        set_home(model, data, physics.ids)
        physics.settle(self.settle_s, self.settle_s + 1.0)
        self._perception = None

    # ------------------------------------------------------------------ specs
    def action_spec(self, physics: KitchenPhysics) -> specs.BoundedArray:
        """7 arm joint targets (rad) and the gripper gap command (m), bounded by the servos."""
        ids = physics.ids
        act = [*ids.arm_actuator_ids.tolist(), ids.gripper_actuator_id]
        if act != list(range(physics.model.nu)):
            raise RuntimeError(f"unexpected actuator order {act} in the kitchen model")
        low, high = physics.model.actuator_ctrlrange.T
        return specs.BoundedArray(
            (len(act),), np.float64, low.copy(), high.copy(), name="joint_targets_and_gripper"
        )

    def observation_spec(self, physics: KitchenPhysics) -> collections.OrderedDict:
        n = self.scene.n_objects
        return collections.OrderedDict(
            arm_qpos=specs.Array((N_ARM,), np.float64, "arm_qpos"),
            arm_qvel=specs.Array((N_ARM,), np.float64, "arm_qvel"),
            gripper_gap=specs.Array((1,), np.float64, "gripper_gap"),
            object_poses=specs.Array((n, 7), np.float64, "object_poses"),
            symbolic=specs.BoundedArray((len(self.atoms),), np.int8, 0, 1, "symbolic"),
            tower_height=specs.BoundedArray((1,), np.float64, 0, self._others, "tower_height"),
        )

    # ------------------------------------------------------------------ per step
    def before_step(self, action: np.ndarray, physics: KitchenPhysics) -> None:
        """Send the 8 commands to the servos (MuJoCo clamps them to the servo ranges).

        Raises `ValueError` for a wrong shape or a non-finite value.
        """
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (physics.model.nu,) or not np.isfinite(action).all():
            raise ValueError(
                f"action must be {physics.model.nu} finite numbers (7 joint targets in rad, "
                f"the gripper gap in m), got {action!r}"
            )
        physics.set_control(action)

    def perception(self, physics: KitchenPhysics) -> Perception:
        """The perceived state at the physics' current time (computed once per time)."""
        if self._perception is None or self._perceived_at != physics.data.time:
            self._perception = physics.perceive()
            self._perceived_at = float(physics.data.time)
        return self._perception

    def get_observation(self, physics: KitchenPhysics) -> collections.OrderedDict:
        perception = self.perception(physics)
        symbolic = np.zeros(len(self.atoms), np.int8)
        for atom in perception.fluent:
            j = self._index.get(atom)
            if j is not None:
                symbolic[j] = 1
        tower = len(perception.tower(self.scene.tower_base))
        return collections.OrderedDict(
            arm_qpos=physics.arm_qpos(),
            arm_qvel=physics.arm_qvel(),
            gripper_gap=np.array([physics.gripper_gap()]),
            object_poses=physics.object_poses(),
            symbolic=symbolic,
            tower_height=np.array([float(tower)]),
        )

    def get_reward(self, physics: KitchenPhysics) -> float:
        """Progress towards the goal, 1 at it: the fraction of its literals that hold, or of
        the other objects standing in the tower (the paper's goal, the tower template)."""
        perception = self.perception(physics)
        if self.goal is None or self.goal.template == "tower":
            return len(perception.tower(self.scene.tower_base)) / self._others
        return literals_held(self.goal, perception.atoms) / len(self.goal.literals)

    def goal_reached(self, physics: KitchenPhysics) -> bool:
        """The goal holds in the perceived state (the paper's tower: its atoms, and every
        object has a symbol; a scene's goal: `check_perception`)."""
        perception = self.perception(physics)
        if self.goal is not None:
            return check_perception(self.scene, self.goal, perception).reached
        return not perception.anomalies and self._goal <= perception.fluent

    def get_termination(self, physics: KitchenPhysics) -> float | None:
        return 0.0 if self.goal_reached(physics) else None
