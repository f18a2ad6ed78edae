"""The `PhysicalState` of a compiled kitchen world, measured from MuJoCo's data alone.

Why a module of its own: the macro-action backend (`MujocoBackend.physical_state`) and the
low-level dm_control track (`utamp_gym.dm`) read the same model, and perception must see the
same abstraction in both. `measure_state` turns poses and contact forces into supports and
containment; the grasp comes from the caller: the backend knows which grasp its pick skill
made, while `measured_grasp` infers one from contacts for a robot driven joint by joint.
"""

from __future__ import annotations

import mujoco
import numpy as np

from utamp_gym.contract.state import FLOOR, Grasp, PhysicalState
from utamp_gym.robot.panda_mjcf import PandaIds
from utamp_gym.scene.geometry import FINGER_PAIRS, NORMALS, SIDES, axis_of
from utamp_gym.sim.bodies import object_prims
from utamp_gym.sim.control import MIN_GAP
from utamp_gym.sim.world import World, rests_on_top, stack_from_poses

FLOOR_BELOW = -0.05  # m: an unsupported object this far below the table top fell off it


def object_poses(world: World, data: mujoco.MjData) -> dict[str, np.ndarray]:
    """Object name -> [x, y, z, qw, qx, qy, qz] of its frame in the world."""
    return {n: np.concatenate([data.xpos[b], data.xquat[b]]) for n, b in world.body_ids.items()}


def measure_state(
    world: World,
    data: mujoco.MjData,
    *,
    held: Grasp | None,
    gripper_gap: float,
    scratch: mujoco.MjData | None = None,
) -> PhysicalState:
    """Poses, what carries each object (contact forces), containment, and the given grasp.

    `scratch` (an `MjData` of the same model) avoids allocating a forwarded copy.
    """
    stack = stack_from_poses(world, data, scratch=scratch)
    supports: dict[str, str | None] = {}
    for name, support in stack.items():
        below_table = data.xpos[world.body_ids[name]][2] < FLOOR_BELOW
        supports[name] = FLOOR if support is None and below_table else support
    on_top = {
        n: s not in (None, FLOOR) and rests_on_top(world, data, n, s) for n, s in supports.items()
    }
    poses = {n: tuple(float(v) for v in p) for n, p in object_poses(world, data).items()}
    return PhysicalState(poses, supports, on_top, held, gripper_gap)


def gripper_gap(data: mujoco.MjData, ids: PandaIds) -> float:
    """Current finger gap (m)."""
    return float(data.qpos[ids.finger_qpos_adr].sum())


def measured_grasp(
    world: World,
    data: mujoco.MjData,
    ids: PandaIds,
    supports: dict[str, str | None] | None = None,
) -> Grasp | None:
    """The grasp the hand has now, inferred from contacts; None if it carries nothing.

    An object is held when both fingers touch it, the fingers are held apart by it (gap
    above `control.MIN_GAP`) and nothing else carries it (`supports[obj]` is None; pass the
    supports from `measure_state` or they are measured here). The member is the one whose
    geoms the fingers touch; the palm part is the object side facing the hand (against the
    TCP's approach axis), the finger parts the canonical pair (`FINGER_PAIRS`) along the
    finger axis (TCP y).
    """
    if gripper_gap(data, ids) <= MIN_GAP:
        return None
    model = world.model
    left, right = (int(model.geom_bodyid[g]) for g in ids.finger_pad_geom_ids)
    touched: dict[str, dict[int, set[int]]] = {}  # object -> finger body -> object geoms
    for i in range(data.ncon):
        g1, g2 = int(data.contact[i].geom[0]), int(data.contact[i].geom[1])
        for finger_geom, other in ((g1, g2), (g2, g1)):
            finger = int(model.geom_bodyid[finger_geom])
            obj = world.object_of_geom(other)
            if finger in (left, right) and obj is not None:
                touched.setdefault(obj, {}).setdefault(finger, set()).add(other)
    held = [o for o, by in touched.items() if len(by) == 2]
    if not held:
        return None
    if supports is None:
        supports = dict(stack_from_poses(world, data))
    free = [o for o in held if supports.get(o) is None]
    if not free:
        return None
    obj = free[0]
    geoms = set().union(*touched[obj].values())
    members = [p.member for p in object_prims(world.scene.type_of(obj))]
    by_geom = dict(zip(world.geom_ids[obj], members, strict=True))
    touched_members = [by_geom[g] for g in sorted(geoms)]
    member = max(set(touched_members), key=touched_members.count)
    rot = data.xmat[world.body_ids[obj]].reshape(3, 3)
    tcp = data.site_xmat[ids.tcp_site_id].reshape(3, 3)
    approach, finger_axis = tcp[:, 2], tcp[:, 1]

    def along(side: str, direction: np.ndarray) -> float:
        return float((rot @ np.asarray(NORMALS[side], dtype=float)) @ direction)

    palm = max(SIDES, key=lambda s: along(s, -approach))
    f1, f2 = max(
        (p for p in FINGER_PAIRS if axis_of(p[0]) != axis_of(palm)),
        key=lambda p: abs(along(p[0], finger_axis)),
    )
    return Grasp(obj, member, palm, f1, f2)


__all__ = ["FLOOR_BELOW", "gripper_gap", "measure_state", "measured_grasp", "object_poses"]
