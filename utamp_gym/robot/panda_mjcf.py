"""Build the Franka Panda into a MuJoCo world spec from the same URDF Pinocchio uses.

`add_panda` loads example-robot-data's URDF with `MjSpec.from_file`, makes it
simulate well (position actuators, gravity compensation, armature, a coupled
two-finger gripper with one force-limited actuator, high-friction finger pads,
SRDF contact exclusions) and attaches it to the caller's world spec. Grasps hold
by contact and friction only.

The arm's gravity compensation is the controller's torque, as on the real robot: it
goes through the actuators (`actuatorgravcomp`), and each joint's total torque (servo
plus compensation) is clamped to the URDF's effort limit (87 N·m joints 1-4, 12 N·m
joints 5-7). What the arm can hold is therefore bounded by its joint torques; the load
on the hand is estimated from them in `utamp_gym.sim.payload`.

The actuators' velocity gains are integrated implicitly only by the `implicitfast`
and `implicit` integrators; use one of them (dt = 0.002 s is the tested step).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from utamp_gym.errors import AssetError, SimulationError
from utamp_gym.robot.assets import PandaAssets, panda_assets, srdf_disabled_collisions
from utamp_gym.robot.kinematics import ARM_JOINTS, FINGER_JOINTS, HOME_Q, TCP_FRAME

# Arm position servos: stiffness kp (N·m/rad) and damping kv (N·m·s/rad), per joint.
# kv/kp = 0.05 s: each joint lags a moving setpoint by ~50 ms and settles overdamped.
ARM_KP = (4500.0, 4500.0, 3500.0, 3500.0, 2000.0, 2000.0, 2000.0)
ARM_KV = (225.0, 225.0, 175.0, 175.0, 100.0, 100.0, 100.0)
ARM_ARMATURE = 0.1  # kg·m², reflected rotor inertia; keeps the light wrist stable at dt=0.002
ARM_DAMPING = 1.0  # N·m·s/rad joint friction-like damping
# Gripper: one servo on the finger gap (m) = q_finger1 + q_finger2, fingers coupled 1:1.
GRIPPER_FORCE = 70.0  # N each finger presses on a grasped object (Franka Hand, continuous)
GRIPPER_MAX_GAP = 0.08  # m, fully open
GRIPPER_KP = GRIPPER_FORCE / 0.007  # N/m; full force once the gap error exceeds 7 mm
GRIPPER_KV = 40.0  # N·s/m on the gap: ~critically damped fingers
FINGER_ARMATURE = 0.02  # kg, reflected drive inertia; keeps the stiff finger servo stable
# The gap command goes through a first-order filter (time constant, s) so free finger
# motion never saturates the force (which would cancel the servo damping): closing on an
# object from fully open reaches it at <= 0.16 m/s per finger and squeezes within ~0.15 s.
GRIPPER_FILTER_TIME = 0.25
PAD_FRICTION = (1.5, 0.01, 0.0001)  # sliding, torsional (m), rolling (m)
PAD_CONDIM = 4  # sliding + torsional friction: a held object cannot pivot freely
#: Finger-pad contact time constant (s) and damping ratio: 3 dt at dt = 0.002. At 2 dt
#: (MuJoCo's stability limit) pads squeezing a light member that can turn freely (a mug's
#: handle) chatter and the member can squirt out (~1 in 100 grasps measured); 3 dt: 0/120.
PAD_SOLREF = (0.006, 1.0)
PAD_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)  # stiff: ~0.1 mm penetration at 70 N, little creep
URDF_PAD_HALF_SIZE = (0.00875, 0.0076, 0.00925)  # the "rubber tip" collision box


@dataclass(frozen=True)
class PandaIds:
    """Ids and addresses of one compiled Panda (see `PandaHandles.bind`)."""

    arm_joint_ids: np.ndarray
    arm_qpos_adr: np.ndarray
    arm_dof_adr: np.ndarray
    finger_qpos_adr: np.ndarray
    finger_dof_adr: np.ndarray
    arm_actuator_ids: np.ndarray
    gripper_actuator_id: int
    gripper_act_adr: int  # index in data.act of the filtered gap command (-1: none)
    tcp_site_id: int
    tcp_body_id: int
    hand_body_ids: np.ndarray  # link7, link8, hand, tcp, fingers: may touch a held object
    body_ids: np.ndarray  # every robot body (link0 .. fingers)
    geom_ids: np.ndarray  # every robot collision geom
    finger_pad_geom_ids: np.ndarray  # (left, right)
    finger_geom_ids: np.ndarray


@dataclass(frozen=True)
class PandaHandles:
    """Full element names of a Panda added with `add_panda` (valid before compiling)."""

    prefix: str
    arm_joints: tuple[str, ...]
    finger_joints: tuple[str, str]
    arm_actuators: tuple[str, ...]
    gripper_actuator: str
    gripper_tendon: str
    tcp_site: str
    tcp_body: str
    hand_body: str
    finger_bodies: tuple[str, str]
    finger_pad_geoms: tuple[str, str]
    home_q: tuple[float, ...] = HOME_Q

    def bind(self, model: mujoco.MjModel) -> PandaIds:
        """Resolve names to ids in a compiled model; raises `SimulationError` if absent."""

        def ident(kind: mujoco.mjtObj, name: str) -> int:
            idx = mujoco.mj_name2id(model, kind, name)
            if idx < 0:
                raise SimulationError(f"Panda element '{name}' ({kind.name}) not in the model")
            return idx

        jnt, act = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_ACTUATOR
        body, geom = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM
        arm = np.array([ident(jnt, n) for n in self.arm_joints])
        fingers = np.array([ident(jnt, n) for n in self.finger_joints])
        tcp_body = ident(body, self.tcp_body)
        body_ids = robot_body_ids(model, self.prefix)
        hand_names = ("panda_link7", "panda_link8", "panda_hand", TCP_FRAME)
        hand = [ident(body, self.prefix + n) for n in hand_names]
        hand += [ident(body, n) for n in self.finger_bodies]
        finger_bodies = [ident(body, n) for n in self.finger_bodies]
        return PandaIds(
            arm_joint_ids=_frozen(arm),
            arm_qpos_adr=_frozen(model.jnt_qposadr[arm]),
            arm_dof_adr=_frozen(model.jnt_dofadr[arm]),
            finger_qpos_adr=_frozen(model.jnt_qposadr[fingers]),
            finger_dof_adr=_frozen(model.jnt_dofadr[fingers]),
            arm_actuator_ids=_frozen(np.array([ident(act, n) for n in self.arm_actuators])),
            gripper_actuator_id=ident(act, self.gripper_actuator),
            gripper_act_adr=int(model.actuator_actadr[ident(act, self.gripper_actuator)]),
            tcp_site_id=ident(mujoco.mjtObj.mjOBJ_SITE, self.tcp_site),
            tcp_body_id=tcp_body,
            hand_body_ids=_frozen(np.array(sorted(hand))),
            body_ids=_frozen(body_ids),
            geom_ids=_frozen(robot_geom_ids(model, self.prefix)),
            finger_pad_geom_ids=_frozen(np.array([ident(geom, n) for n in self.finger_pad_geoms])),
            finger_geom_ids=_frozen(np.flatnonzero(np.isin(model.geom_bodyid, finger_bodies))),
        )


def _frozen(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=int)
    arr.flags.writeable = False
    return arr


def robot_body_ids(model: mujoco.MjModel, prefix: str) -> np.ndarray:
    """Ids of the bodies whose name starts with `prefix` (e.g. "panda/")."""
    return np.array(
        [
            b
            for b in range(model.nbody)
            if (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "").startswith(prefix)
        ],
        dtype=int,
    )


def robot_geom_ids(model: mujoco.MjModel, prefix: str) -> np.ndarray:
    """Ids of the geoms attached to bodies whose name starts with `prefix`."""
    return np.flatnonzero(np.isin(model.geom_bodyid, robot_body_ids(model, prefix)))


def load_panda_spec(assets: PandaAssets | None = None) -> mujoco.MjSpec:
    """The Panda URDF as an `MjSpec` (absolute mesh paths, static bodies kept), unmodified."""
    assets = assets or panda_assets()
    try:
        spec = mujoco.MjSpec.from_file(str(assets.urdf))
    except (ValueError, RuntimeError) as exc:
        raise AssetError(f"MuJoCo could not parse {assets.urdf}: {exc}") from exc
    spec.compiler.fusestatic = False
    for mesh in spec.meshes:
        path = assets.resolve_uri(mesh.file)
        if not path.is_file():
            raise AssetError(f"Panda mesh '{mesh.file}' not found at {path}")
        mesh.file = str(path)
    return spec


def add_panda(
    world: mujoco.MjSpec,
    *,
    base_pos: Sequence[float] = (0.0, 0.0, 0.0),
    base_quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0),
    name_prefix: str = "panda/",
    assets: PandaAssets | None = None,
) -> PandaHandles:
    """Attach a simulation-ready Panda to `world` at `base_pos`; return its element names.

    Arm actuators are position servos (ctrl = joint angle, rad); the gripper actuator's
    ctrl is the finger gap in metres, 0 (squeeze with `GRIPPER_FORCE`) .. 0.08 (open).
    """
    spec = load_panda_spec(assets)
    _tune_joints_and_bodies(spec)
    pads = _name_geoms(spec)
    _add_arm_actuators(spec)
    _add_gripper(spec)
    for link1, link2 in srdf_disabled_collisions(assets):
        spec.add_exclude(bodyname1=link1, bodyname2=link2)
    spec.body(TCP_FRAME).add_site(name="tcp", size=[0.005, 0, 0], rgba=[1, 0, 0, 0.5], group=5)
    frame = world.worldbody.add_frame(pos=list(base_pos), quat=list(base_quat))
    try:
        world.attach(spec, prefix=name_prefix, frame=frame)
    except ValueError as exc:
        raise SimulationError(
            f"cannot attach the Panda with prefix '{name_prefix}': {exc}"
        ) from exc
    p = name_prefix
    return PandaHandles(
        prefix=p,
        arm_joints=tuple(p + n for n in ARM_JOINTS),
        finger_joints=(p + FINGER_JOINTS[0], p + FINGER_JOINTS[1]),
        arm_actuators=tuple(p + n.replace("panda_joint", "actuator") for n in ARM_JOINTS),
        gripper_actuator=p + "gripper",
        gripper_tendon=p + "gripper_gap",
        tcp_site=p + "tcp",
        tcp_body=p + TCP_FRAME,
        hand_body=p + "panda_hand",
        finger_bodies=(p + "panda_leftfinger", p + "panda_rightfinger"),
        finger_pad_geoms=(p + pads[0], p + pads[1]),
    )


def _tune_joints_and_bodies(spec: mujoco.MjSpec) -> None:
    for body in spec.bodies:
        if body.name != "world":
            body.gravcomp = 1.0  # the Franka controller compensates the robot's own weight
    for name in ARM_JOINTS:
        joint = spec.joint(name)
        joint.armature = ARM_ARMATURE
        joint.damping = _damping(joint.damping, ARM_DAMPING)
        # The compensation is the controller's torque, not buoyancy: it is added to the
        # actuator force and the sum is clamped to the joint's torque limit.
        joint.actgravcomp = True
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.actfrcrange = [-_effort(joint), _effort(joint)]
    for name in FINGER_JOINTS:
        joint = spec.joint(name)
        joint.armature = FINGER_ARMATURE
        joint.damping = _damping(joint.damping, 1.0)


def _effort(joint: mujoco.MjsJoint) -> float:
    """The joint's torque limit (N·m): the URDF's effort, 87 (joints 1-4) or 12 (5-7)."""
    return float(joint.actfrcrange[1]) or (87.0 if int(joint.name[-1]) <= 4 else 12.0)


def _damping(current: object, value: float) -> object:
    """Joint damping is a scalar in older mujoco and a 3-vector (polynomial) in newer."""
    if np.ndim(current) == 0:
        return value
    out = np.zeros(np.shape(current))
    out[0] = value
    return out


def _name_geoms(spec: mujoco.MjSpec) -> tuple[str, str]:
    """Name every collision geom `<link>_collision<i>`; the finger tips become pads."""
    counts: dict[str, int] = {}
    pads: dict[str, str] = {}
    for geom in spec.geoms:
        link = geom.parent.name
        index = counts.get(link, 0)
        counts[link] = index + 1
        is_pad = (
            link in ("panda_leftfinger", "panda_rightfinger")
            and geom.type == mujoco.mjtGeom.mjGEOM_BOX
            and np.allclose(geom.size, URDF_PAD_HALF_SIZE, atol=1e-6)
        )
        geom.name = f"{link}_pad" if is_pad else f"{link}_collision{index}"
        if is_pad:
            geom.friction = list(PAD_FRICTION)
            geom.condim = PAD_CONDIM
            geom.priority = 1  # the pad's friction and condim govern pad contacts
            geom.solref = list(PAD_SOLREF)
            geom.solimp = list(PAD_SOLIMP)
            geom.rgba = [0.2, 0.2, 0.2, 1]
            pads[link] = geom.name
    if set(pads) != {"panda_leftfinger", "panda_rightfinger"}:
        raise AssetError("Panda URDF finger-tip collision boxes not found (URDF changed?)")
    return pads["panda_leftfinger"], pads["panda_rightfinger"]


def _add_arm_actuators(spec: mujoco.MjSpec) -> None:
    for name, kp, kv in zip(ARM_JOINTS, ARM_KP, ARM_KV, strict=True):
        joint = spec.joint(name)
        effort = _effort(joint)
        act = spec.add_actuator(
            name=name.replace("panda_joint", "actuator"),
            target=name,
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
        )
        act.set_to_position(kp=kp, kv=kv)
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.ctrlrange = list(joint.range)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-effort, effort]


def _add_gripper(spec: mujoco.MjSpec) -> None:
    # URDF <mimic> becomes a joint equality in recent mujoco; replace it with a named one.
    for eq in list(spec.equalities):
        if eq.type == mujoco.mjtEq.mjEQ_JOINT and {eq.name1, eq.name2} == set(FINGER_JOINTS):
            spec.delete(eq)
    data = np.zeros(len(mujoco.MjSpec().add_equality().data))  # size differs across versions
    data[1] = 1.0  # finger2 = finger1
    spec.add_equality(
        name="finger_coupling",
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1=FINGER_JOINTS[1],
        name2=FINGER_JOINTS[0],
        data=list(data),
        solref=[0.005, 1.0],
    )
    tendon = spec.add_tendon(name="gripper_gap")
    for name in FINGER_JOINTS:
        tendon.wrap_joint(name, 1.0)
    act = spec.add_actuator(
        name="gripper", target="gripper_gap", trntype=mujoco.mjtTrn.mjTRN_TENDON
    )
    act.set_to_position(kp=GRIPPER_KP, kv=GRIPPER_KV)
    act.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
    act.dynprm[0] = GRIPPER_FILTER_TIME
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    act.ctrlrange = [0.0, GRIPPER_MAX_GAP]
    act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    act.forcerange = [-GRIPPER_FORCE, GRIPPER_FORCE]


def apply_recommended_options(world: mujoco.MjSpec, timestep: float = 0.002) -> None:
    """Physics options the Panda is tuned for: implicitfast at 2 ms, elliptic friction cones.

    With `impratio` 10 a 0.3-1 kg box held at 70 N creeps < 0.05 mm/s; with the
    default pyramidal cones and impratio 1 it creeps ~0.4 mm/s (still held).
    """
    world.option.timestep = timestep
    world.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    world.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    world.option.impratio = 10.0


def set_home(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    ids: PandaIds,
    q: Sequence[float] = HOME_Q,
    gap: float = GRIPPER_MAX_GAP,
) -> None:
    """Put the arm at `q` with fingers at `gap` (qpos, zero velocity, matching ctrl)."""
    q = np.asarray(q, dtype=float)
    data.qpos[ids.arm_qpos_adr] = q
    data.qvel[ids.arm_dof_adr] = 0.0
    data.qpos[ids.finger_qpos_adr] = gap / 2
    data.qvel[ids.finger_dof_adr] = 0.0
    data.ctrl[ids.arm_actuator_ids] = q
    data.ctrl[ids.gripper_actuator_id] = gap
    if ids.gripper_act_adr >= 0:
        data.act[ids.gripper_act_adr] = gap
    mujoco.mj_forward(model, data)
