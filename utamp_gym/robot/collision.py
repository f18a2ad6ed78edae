"""MuJoCo collision checking of Panda arm configurations, with an optional held object.

`CollisionChecker` owns a copy of the model (robot geoms get a collision margin)
and a scratch `MjData`; it never touches the simulation's data. Counted contacts:
robot (or held object) vs world closer than `margin`, and robot self-contacts
(pairs not excluded by the SRDF) closer than `self_margin`. A held object moves
rigidly with the TCP; its contacts with the hand are ignored.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.errors import GroundingError
from utamp_gym.robot.panda_mjcf import PandaIds

Pair = tuple[int, int]


@dataclass(frozen=True)
class Contact:
    """One counted contact: geom ids (robot-side first), signed distance (m), kind."""

    geom1: int
    geom2: int
    dist: float
    kind: str  # "world" | "self"


class CollisionChecker:
    """Validity of arm configurations against the world state last given by `sync`."""

    def __init__(
        self,
        model: mujoco.MjModel,
        ids: PandaIds,
        *,
        margin: float = 0.01,
        self_margin: float = 0.002,
    ):
        if margin < 0 or self_margin < 0:
            raise GroundingError(f"margins must be >= 0 (got {margin}, {self_margin})")
        self.model = copy.deepcopy(model)
        self.data = mujoco.MjData(self.model)
        self.ids = ids
        self.margin = float(margin)
        self.self_margin = float(self_margin)
        self._gen_margin = max(self.margin, self.self_margin)
        self._base_margin = self.model.geom_margin.copy()
        self.model.geom_margin[ids.geom_ids] = np.maximum(
            self._base_margin[ids.geom_ids], self._gen_margin
        )
        ng = self.model.ngeom
        self._robot = np.zeros(ng, dtype=bool)
        self._robot[ids.geom_ids] = True
        self._hand = np.isin(self.model.geom_bodyid, ids.hand_body_ids)
        self._held = np.zeros(ng, dtype=bool)
        self._held_geoms = np.zeros(0, dtype=int)
        self.held_body: int | None = None
        self.detach()
        self.tolerance: dict[Pair, float] = {}  # pair -> smallest allowed distance
        self.checks = 0
        self.lower = self.model.jnt_range[ids.arm_joint_ids, 0].copy()
        self.upper = self.model.jnt_range[ids.arm_joint_ids, 1].copy()

    # ------------------------------------------------------------ world state
    def sync(self, data: mujoco.MjData) -> None:
        """Copy the world state (qpos, mocap poses) from the simulation's data."""
        self.set_world_state(data.qpos, data.mocap_pos, data.mocap_quat)

    def set_world_state(
        self,
        qpos: np.ndarray,
        mocap_pos: np.ndarray | None = None,
        mocap_quat: np.ndarray | None = None,
    ) -> None:
        self.data.qpos[:] = qpos
        if mocap_pos is not None and self.model.nmocap:
            self.data.mocap_pos[:] = mocap_pos
        if mocap_quat is not None and self.model.nmocap:
            self.data.mocap_quat[:] = mocap_quat
        mujoco.mj_kinematics(self.model, self.data)

    def tcp_pose(self, q: np.ndarray | None = None) -> np.ndarray:
        """4x4 world pose of the TCP site at arm configuration `q` (default: current)."""
        if q is not None:
            self.data.qpos[self.ids.arm_qpos_adr] = q
            mujoco.mj_kinematics(self.model, self.data)
        out = np.eye(4)
        out[:3, :3] = self.data.site_xmat[self.ids.tcp_site_id].reshape(3, 3)
        out[:3, 3] = self.data.site_xpos[self.ids.tcp_site_id]
        return out

    def body_pose(self, body_id: int) -> np.ndarray:
        """4x4 world pose of a body in the current world state."""
        out = np.eye(4)
        out[:3, :3] = self.data.xmat[body_id].reshape(3, 3)
        out[:3, 3] = self.data.xpos[body_id]
        return out

    # ------------------------------------------------------------ held object
    def attach(self, body_id: int, tcp_T_obj: np.ndarray | None = None) -> None:
        """Treat free body `body_id` (with its subtree) as rigidly held at `tcp_T_obj` (4x4).

        Without `tcp_T_obj` the relative pose is taken from the current world state.
        """
        m = self.model
        if not 0 < body_id < m.nbody:
            raise GroundingError(f"cannot attach body id {body_id}: no such movable body")
        jnt = int(m.body_jntadr[body_id])
        if jnt < 0 or m.jnt_type[jnt] != mujoco.mjtJoint.mjJNT_FREE:
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, body_id)
            raise GroundingError(f"cannot attach body '{name}': it has no free joint")
        self.detach()
        mujoco.mj_kinematics(m, self.data)
        if tcp_T_obj is None:
            tcp_T_obj = np.linalg.inv(self.tcp_pose()) @ self.body_pose(body_id)
        subtree = [b for b in range(m.nbody) if _in_subtree(m, b, body_id)]
        geoms = np.flatnonzero(np.isin(m.geom_bodyid, subtree))
        geoms = geoms[(m.geom_contype[geoms] | m.geom_conaffinity[geoms]) > 0]
        self._held_geoms = geoms
        self._held_qpos_adr = int(m.jnt_qposadr[jnt])
        self._held_qpos0 = self.data.qpos[self._held_qpos_adr : self._held_qpos_adr + 7].copy()
        self._held_tcp_T_obj = np.array(tcp_T_obj, dtype=float)
        self.held_body = body_id
        self._held[geoms] = True
        m.geom_margin[geoms] = np.maximum(self._base_margin[geoms], self._gen_margin)

    def detach(self) -> None:
        """Forget the held object and put it back where the world state had it."""
        if self.held_body is not None:
            adr = self._held_qpos_adr
            self.data.qpos[adr : adr + 7] = self._held_qpos0
        g = self._held_geoms
        self.model.geom_margin[g] = self._base_margin[g]
        self._held[g] = False
        self._held_geoms = np.zeros(0, dtype=int)
        self._held_qpos_adr = -1
        self._held_tcp_T_obj = np.eye(4)
        self.held_body = None

    # ------------------------------------------------------------ checks
    def _collide(self, q: np.ndarray) -> None:
        m, d = self.model, self.data
        d.qpos[self.ids.arm_qpos_adr] = q
        mujoco.mj_kinematics(m, d)
        if self.held_body is not None:
            # Put the held body's free joint where the hand carries it, then redo kinematics
            # (the mid-phase reads body as well as geom poses, so writing geoms is not enough).
            world = self.tcp_pose() @ self._held_tcp_T_obj
            adr = self._held_qpos_adr
            d.qpos[adr : adr + 3] = world[:3, 3]
            mujoco.mju_mat2Quat(d.qpos[adr + 3 : adr + 7], world[:3, :3].ravel())
            mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        self.checks += 1

    def contacts(self, q: np.ndarray, *, tolerate: bool = True) -> list[Contact]:
        """Counted contacts at `q` (those within the margins and not tolerated)."""
        self._collide(np.asarray(q, dtype=float))
        n = self.data.ncon
        if n == 0:
            return []
        geom = self.data.contact.geom[:n]
        dist = self.data.contact.dist[:n]
        mine = self._robot | self._held
        m1, m2 = mine[geom[:, 0]], mine[geom[:, 1]]
        world = (m1 ^ m2) & (dist < self.margin)
        # Self: robot-robot, or held-vs-robot except the hand holding it.
        h1, h2 = self._held[geom[:, 0]], self._held[geom[:, 1]]
        hand1, hand2 = self._hand[geom[:, 0]], self._hand[geom[:, 1]]
        ignored = (h1 & hand2) | (h2 & hand1) | (h1 & h2)
        selfc = m1 & m2 & ~ignored & (dist < self.self_margin)
        out = []
        for i in np.flatnonzero(world | selfc):
            g1, g2 = int(geom[i, 0]), int(geom[i, 1])
            if not mine[g1]:
                g1, g2 = g2, g1
            pair = (min(g1, g2), max(g1, g2))
            if tolerate and dist[i] >= self.tolerance.get(pair, np.inf):
                continue
            out.append(Contact(g1, g2, float(dist[i]), "world" if world[i] else "self"))
        return out

    def is_valid(self, q: np.ndarray) -> bool:
        """True if `q` is inside the joint limits and has no counted contact."""
        q = np.asarray(q, dtype=float)
        if np.any(q < self.lower - 1e-9) or np.any(q > self.upper + 1e-9):
            return False
        return not self.contacts(q)

    def describe(self, contacts: list[Contact]) -> str:
        """Human-readable list of contacts, by geom (or body) name."""
        parts = [
            f"{self._name(c.geom1)}~{self._name(c.geom2)} ({c.kind}, {c.dist * 1000:.1f} mm)"
            for c in contacts[:6]
        ]
        return ", ".join(parts) + (" ..." if len(contacts) > 6 else "")

    def _name(self, g: int) -> str:
        name = mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_GEOM, g)
        if name:
            return name
        body = int(self.model.geom_bodyid[g])
        return f"{mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, body)}#geom{g}"

    @contextmanager
    def tolerating(self, *configs: np.ndarray, slack: float = 1e-4) -> Iterator[None]:
        """Within the block, contacts present at `configs` may persist but not deepen.

        This relaxes the margin at a start (or goal) state that is already inside it,
        e.g. a held object resting on the table or fingers around an object to grasp.
        """
        saved = dict(self.tolerance)
        for q in configs:
            for c in self.contacts(q, tolerate=False):
                pair = (min(c.geom1, c.geom2), max(c.geom1, c.geom2))
                self.tolerance[pair] = min(self.tolerance.get(pair, np.inf), c.dist - slack)
        try:
            yield
        finally:
            self.tolerance = saved


def _in_subtree(model: mujoco.MjModel, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return False
