"""`KitchenPhysics`: a `dm_control.mujoco.Physics` over the model our world builder compiles.

Why a subclass: dm_control tasks read the simulation through their Physics, so the joint
state, the object poses and the perceived symbolic state are methods here, computed with the
same code as the macro-action backend (`utamp_gym.sim.physical`), only with the grasp
measured from contacts (`measured_grasp`) instead of remembered from a pick skill.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
from dm_control import mujoco as dm_mujoco
from dm_control.mujoco import wrapper

from utamp_gym.contract.state import PhysicalState
from utamp_gym.perception.abstraction import Perception, perceive
from utamp_gym.robot.panda_mjcf import PandaIds, add_panda
from utamp_gym.scene.model import Scene
from utamp_gym.sim.gl import ensure_dm_control_gl
from utamp_gym.sim.physical import gripper_gap, measure_state, measured_grasp, object_poses
from utamp_gym.sim.world import World, build_world_spec, compile_world

SETTLE_SPEED = 0.01  # m/s (or rad/s): objects slower than this have settled
SETTLE_CHECK = 0.05  # s between settle checks


class KitchenPhysics(dm_mujoco.Physics):
    """The kitchen world (table, objects, Panda) as a dm_control Physics.

    Build it with `KitchenPhysics.build(scene)`; `world` and `ids` give the name maps of
    the objects and the Panda. Stepping is dm_control's (`step`, `set_control`).
    """

    world: World
    ids: PandaIds

    @classmethod
    def build(cls, scene: Scene, *, timestep: float = 0.002) -> KitchenPhysics:
        """Compile `scene`'s world (declared poses) with a Panda at the origin."""
        spec, info = build_world_spec(scene, timestep=timestep)
        handles = add_panda(spec)
        world = compile_world(spec, info)
        physics = cls.from_model(wrapper.MjModel(world.model))
        physics._attach(world, handles.bind(world.model))
        return physics

    def _attach(self, world: World, ids: PandaIds) -> None:
        self.world, self.ids = world, ids
        self._scratch = mujoco.MjData(world.model)

    def _make_rendering_contexts(self) -> None:
        """dm_control's GL contexts (made on the first render), on the backend that
        `utamp_gym.sim.gl` chose (dm_control reads ``MUJOCO_GL`` when it is imported)."""
        ensure_dm_control_gl()
        super()._make_rendering_contexts()

    def copy(self, share_model: bool = False) -> Any:
        """A copy (dm_control's), keeping the world's name maps."""
        new = super().copy(share_model=share_model)
        new._attach(self.world, self.ids)
        return new

    # ------------------------------------------------------------------ robot
    def arm_qpos(self) -> np.ndarray:
        """The 7 arm joint angles (rad)."""
        return self.data.qpos[self.ids.arm_qpos_adr].copy()

    def arm_qvel(self) -> np.ndarray:
        """The 7 arm joint velocities (rad/s)."""
        return self.data.qvel[self.ids.arm_dof_adr].copy()

    def gripper_gap(self) -> float:
        """The finger gap (m)."""
        return gripper_gap(self.data.ptr, self.ids)

    # ------------------------------------------------------------------ objects
    def object_poses(self) -> np.ndarray:
        """(n objects, 7): ``[x, y, z, qw, qx, qy, qz]`` per object, in scene order."""
        poses = object_poses(self.world, self.data.ptr)
        return np.array([poses[o.name] for o in self.world.scene.objects])

    def settle(self, min_s: float, max_s: float) -> None:
        """Step (controls unchanged) for `min_s`, then until the objects rest or `max_s`."""
        dt = float(self.model.opt.timestep)
        mujoco.mj_step(self.model.ptr, self.data.ptr, nstep=round(min_s / dt))
        dofs = [self.world.dof_adr[n] for n in self.world.body_ids]
        for _ in range(round((max_s - min_s) / SETTLE_CHECK)):
            if max(float(np.abs(self.data.qvel[a : a + 6]).max()) for a in dofs) < SETTLE_SPEED:
                return
            mujoco.mj_step(self.model.ptr, self.data.ptr, nstep=round(SETTLE_CHECK / dt))

    # ------------------------------------------------------------------ perception
    def physical_state(self) -> PhysicalState:
        """What perception needs (`utamp_gym.sim.physical`), the grasp measured from contacts."""
        world, data = self.world, self.data.ptr
        state = measure_state(
            world, data, held=None, gripper_gap=self.gripper_gap(), scratch=self._scratch
        )
        held = measured_grasp(world, data, self.ids, dict(state.supports))
        if held is None:
            return state
        return PhysicalState(state.poses, state.supports, state.on_top, held, state.gripper_gap)

    def perceive(self) -> Perception:
        """The symbolic state of the scene as perceived now (`utamp_gym.perception`)."""
        return perceive(self.world.scene, self.physical_state())
