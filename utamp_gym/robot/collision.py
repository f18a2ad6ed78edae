"""MuJoCo collision checking of Panda arm configurations, with an optional held object.

`CollisionChecker` owns a copy of the model (robot geoms get a collision margin)
and a scratch `MjData`; it never touches the simulation's data. Counted contacts:
robot (or held object) vs world closer than `margin`, and robot self-contacts
(pairs not excluded by the SRDF) closer than `self_margin`. A held object moves
rigidly with the TCP; its contacts with the hand are ignored. It may be checked at
other poses in the hand as well (`attach`'s `also`: where it may turn while carried).
"""

from __future__ import annotations

import copy
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.errors import GroundingError
from utamp_gym.robot.panda_mjcf import PandaIds

Pair = tuple[int, int]

# Geom classes and what a contact between two classes means (0: ignored, 1: world, 2: self).
_WORLD, _ROBOT, _HAND, _HELD = 0, 1, 2, 3
_K_WORLD, _K_SELF = 1, 2
_KIND = np.array(
    [
        [0, 1, 1, 1],  # world vs world / robot / hand / held
        [1, 2, 2, 2],  # robot
        [1, 2, 2, 0],  # hand (touching the held object is expected)
        [1, 2, 0, 0],  # held
    ],
    dtype=np.int8,
)
_KIND.flags.writeable = False
_BIT_WORLD, _BIT_ROBOT = 1 << 30, 1 << 29  # private collision bits of the checker's model copy


def _empty(shape: tuple[int, ...], dtype: type) -> np.ndarray:
    out = np.zeros(shape, dtype=dtype)
    out.flags.writeable = False
    return out


_NO_PAIRS, _NO_FLOATS, _NO_KINDS = (
    _empty((0, 2), np.int32),
    _empty((0,), float),
    _empty((0,), np.int8),
)


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
        # geometric queries see every geom: no sleeping islands (`sim.world`) in the copy
        self.model.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        self.data = mujoco.MjData(self.model)
        self.ids = ids
        self.margin = float(margin)
        self.self_margin = float(self_margin)
        self._gen_margin = max(self.margin, self.self_margin)
        self._base_margin = self.model.geom_margin.copy()
        self._base_body_margin = self.model.body_margin.copy()
        # The robot's bodies keep their compiled body_margin (only a held object's is widened,
        # `_widen_bodies`): widening the fingers' (4 geoms each) would count objects within the
        # margin of them too, but it changes the paper suites' seeded rollouts.
        self.model.geom_margin[ids.geom_ids] = np.maximum(
            self._base_margin[ids.geom_ids], self._gen_margin
        )
        self._cls = np.full(self.model.ngeom, _WORLD, dtype=np.int8)
        self._cls[ids.geom_ids] = _ROBOT
        self._cls[np.isin(self.model.geom_bodyid, ids.hand_body_ids)] = _HAND
        self._base_bits = (self.model.geom_contype.copy(), self.model.geom_conaffinity.copy())
        self._use_check_bits(ids.geom_ids)
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
        """Set the world state (full qpos and mocap poses) the checks are made against."""
        self.data.qpos[:] = qpos
        if self.held_body is not None:  # detach() will restore the newly synced pose
            adr = self._held_qpos_adr
            self._held_qpos0 = self.data.qpos[adr : adr + 7].copy()
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
    def attach(
        self,
        body_id: int,
        tcp_T_obj: np.ndarray | None = None,
        also: Sequence[np.ndarray] = (),
    ) -> None:
        """Treat free body `body_id` (with its subtree) as rigidly held at `tcp_T_obj` (4x4).

        Without `tcp_T_obj` the relative pose is taken from the current world state. Its
        contacts at each pose of `also` (4x4 in the TCP frame) count as well.
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
        self._held_also = [np.array(p, dtype=float) for p in also]
        self.held_body = body_id
        self._cls[geoms] = _HELD
        self._set_bits(geoms, robot=True)
        m.geom_margin[geoms] = np.maximum(self._base_margin[geoms], self._gen_margin)
        self._widen_bodies(geoms)

    def _widen_bodies(self, geoms: np.ndarray) -> None:
        """Each body of `geoms` gets at least their margins: MuJoCo's mid-phase bounds a body
        of several geoms by its ``body_margin`` (set when the model compiled), so a wider geom
        margin alone misses pairs of such bodies between the old and the new margin."""
        np.maximum.at(
            self.model.body_margin, self.model.geom_bodyid[geoms], self.model.geom_margin[geoms]
        )

    def detach(self) -> None:
        """Forget the held object and put it back where the world state had it."""
        if self.held_body is not None:
            adr = self._held_qpos_adr
            self.data.qpos[adr : adr + 7] = self._held_qpos0
        g = self._held_geoms
        self.model.geom_margin[g] = self._base_margin[g]
        bodies = self.model.geom_bodyid[g]
        self.model.body_margin[bodies] = self._base_body_margin[bodies]
        self._cls[g] = _WORLD
        self._set_bits(g, robot=False)
        self._held_geoms = np.zeros(0, dtype=int)
        self._held_qpos_adr = -1
        self._held_tcp_T_obj = np.eye(4)
        self._held_also: list[np.ndarray] = []
        self.held_body = None

    # ------------------------------------------------------------ checks
    def _collide(self, q: np.ndarray) -> None:
        m, d = self.model, self.data
        d.qpos[self.ids.arm_qpos_adr] = q
        mujoco.mj_kinematics(m, d)
        if self.held_body is not None:
            self._hold_at(self._held_tcp_T_obj)
        mujoco.mj_collision(m, d)
        self.checks += 1

    def _hold_at(self, tcp_T_obj: np.ndarray) -> None:
        """Put the held body's free joint where the hand carries it at `tcp_T_obj`, then
        redo kinematics (the mid-phase reads body as well as geom poses, so writing geoms is
        not enough)."""
        world = self.tcp_pose() @ tcp_T_obj
        adr = self._held_qpos_adr
        self.data.qpos[adr : adr + 3] = world[:3, 3]
        mujoco.mju_mat2Quat(self.data.qpos[adr + 3 : adr + 7], world[:3, :3].ravel())
        mujoco.mj_kinematics(self.model, self.data)

    def _counted(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Contacts at `q` that count: (geom pairs, distances, kinds), before tolerance;
        the held object's at each of its `also` poses as well."""
        self._collide(q)
        found = [self._kept()]
        for pose in self._held_also:
            self._hold_at(pose)
            mujoco.mj_collision(self.model, self.data)
            geom, dist, kind = self._kept()
            held = (self._cls[geom] == _HELD).any(axis=1)
            found.append((geom[held], dist[held], kind[held]))
        if len(found) == 1:
            return found[0]
        geom, dist, kind = (np.concatenate(parts) for parts in zip(*found, strict=True))
        return geom, dist, kind

    def _kept(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The counted contacts of the last collision pass."""
        n = self.data.ncon
        if n == 0:
            return _NO_PAIRS, _NO_FLOATS, _NO_KINDS
        geom = self.data.contact.geom[:n]
        dist = self.data.contact.dist[:n]
        kind = _KIND[self._cls[geom[:, 0]], self._cls[geom[:, 1]]]
        keep = np.where(
            kind == _K_WORLD, dist < self.margin, (kind == _K_SELF) & (dist < self.self_margin)
        )
        return geom[keep], dist[keep], kind[keep]

    def _tolerated(self, g1: int, g2: int, dist: float) -> bool:
        return dist >= self.tolerance.get((min(g1, g2), max(g1, g2)), np.inf)

    def contacts(self, q: np.ndarray, *, tolerate: bool = True) -> list[Contact]:
        """Counted contacts at `q` (within the margins and, if `tolerate`, not tolerated)."""
        geom, dist, kind = self._counted(np.asarray(q, dtype=float))
        out = []
        for (g1, g2), d, k in zip(geom.tolist(), dist.tolist(), kind.tolist(), strict=True):
            if tolerate and self._tolerated(g1, g2, d):
                continue
            if self._cls[g1] == _WORLD:
                g1, g2 = g2, g1
            out.append(Contact(g1, g2, d, "world" if k == _K_WORLD else "self"))
        return out

    def is_valid(self, q: np.ndarray) -> bool:
        """True if `q` is inside the joint limits and has no counted contact."""
        q = np.asarray(q, dtype=float)
        if ((q < self.lower - 1e-9) | (q > self.upper + 1e-9)).any():
            return False
        geom, dist, _ = self._counted(q)
        if not len(dist):
            return True
        if not self.tolerance:
            return False
        return all(
            self._tolerated(g1, g2, d)
            for (g1, g2), d in zip(geom.tolist(), dist.tolist(), strict=True)
        )

    def _use_check_bits(self, robot_geoms: np.ndarray) -> None:
        """Collision bits so only robot-vs-world and robot-vs-robot pairs are generated."""
        contype, conaff = self._base_bits
        rtype = int(np.bitwise_or.reduce(contype[robot_geoms]))
        raff = int(np.bitwise_or.reduce(conaff[robot_geoms]))
        # A world geom stays checkable iff it could collide with the robot in the scene.
        self._world_collides = ((contype & raff) | (conaff & rtype)) != 0
        self._set_bits(np.flatnonzero(self._cls == _WORLD), robot=False)
        self._set_bits(robot_geoms, robot=True)

    def _set_bits(self, geoms: np.ndarray, *, robot: bool) -> None:
        m = self.model
        if robot:
            m.geom_contype[geoms] = _BIT_WORLD | _BIT_ROBOT
            m.geom_conaffinity[geoms] = _BIT_ROBOT
        else:
            on = self._world_collides[geoms]
            m.geom_contype[geoms] = 0
            m.geom_conaffinity[geoms] = np.where(on, _BIT_WORLD, 0)

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
