"""The MuJoCo world built from a `Scene`: table, objects, light; no robot.

The world's geometry comes from the same catalogue the symbolic layer reads (see
`utamp_gym.sim.bodies`), its initial poses from `Scene.poses`. To add the robot, take
the spec from `build_world_spec`, attach the Panda to it, then call `compile_world`:

    spec, info = build_world_spec(scene, rng=rng)
    handles = add_panda(spec)            # utamp_gym.robot.panda_mjcf
    world = compile_world(spec, info)

Object bodies are named ``obj/<name>``; their frame is the object frame (origin at the
bottom centre of the main body). z = 0 is the table top; the robot base is the origin.
Options match the Panda's tuning: implicitfast, elliptic cones, impratio 10. The pose
queries read `data` as left by `mj_step`/`mj_forward`; `stack_from_poses` forwards a copy.

With ``sleep=True`` (the macro-action backend's choice) MuJoCo's sleeping islands are on:
objects that have come to rest (every velocity below `SLEEP_TOLERANCE` for 10 steps) are
frozen and their contacts with each other and the table are skipped until an awake body
(the robot, a held or falling object) touches them, which wakes the whole island at once.
Most of an episode's objects stand still most of the time, so this removes most contacts
from most steps (`docs/physics-speed.md` has the cost per step with and without).
Sleeping objects keep their poses; their velocities read zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import mujoco
import numpy as np

from utamp_gym.contract.state import TILT_DEG
from utamp_gym.errors import SimulationError, UnknownNameError
from utamp_gym.scene.model import Pose, Scene
from utamp_gym.sim.appearance import (
    ACCENT_MATERIAL,
    Appearance,
    add_materials,
    material_name,
    object_appearance,
)
from utamp_gym.sim.bodies import (
    BODY_PREFIX,
    ROLLING,
    SOLIMP,
    SOLREF,
    TORSIONAL,
    add_object_body,
    friction_of,
    initial_poses,
)
from utamp_gym.sim.cameras import add_scene_cameras

TABLE_GEOM = "table"
#: m/s (MuJoCo's default; rotations count times the body's size): what counts as at rest
#: for sleeping, 10x stricter than the skills' own "settled" (`measure.settle_objects`)
SLEEP_TOLERANCE = 1e-3
FLOOR_Z = -0.75  # m, the floor under the table (objects that fall off land here)
GRAVITY = 9.81


@dataclass(frozen=True)
class WorldInfo:
    """Everything known about a world spec before compiling: the scene, names, initial poses."""

    scene: Scene
    poses: Mapping[str, Pose]  # initial pose of each object (with noise) in the spec
    body_names: Mapping[str, str]
    geom_names: Mapping[str, tuple[str, ...]]
    slot_positions: Mapping[str, np.ndarray]
    table_geom: str = TABLE_GEOM
    appearance: Mapping[str, Appearance] = field(default_factory=dict)  # colour and finish


@dataclass(frozen=True)
class World:
    """A compiled world: model, spec and name -> id maps for the scene's objects."""

    model: mujoco.MjModel
    spec: mujoco.MjSpec
    info: WorldInfo
    body_ids: Mapping[str, int]
    qpos_adr: Mapping[str, int]  # free joint: x y z qw qx qy qz
    dof_adr: Mapping[str, int]  # free joint: vx vy vz wx wy wz
    geom_ids: Mapping[str, list[int]]
    slot_positions: Mapping[str, np.ndarray]
    table_geom_id: int
    body_objects: Mapping[int, str]  # body id -> object name

    @property
    def scene(self) -> Scene:
        return self.info.scene

    def make_data(self) -> mujoco.MjData:
        """Fresh data at the initial state (`model.qpos0`), forwarded."""
        data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, data)
        return data

    def initial_qpos(
        self,
        rng: np.random.Generator | None = None,
        *,
        pos_noise: float = 0.003,
        yaw_noise_deg: float = 2.0,
    ) -> np.ndarray:
        """`model.qpos0` with object poses re-drawn from the scene (new noise, no recompiling)."""
        qpos = self.model.qpos0.copy()
        for name, pose in initial_poses(self.scene, rng, pos_noise, yaw_noise_deg).items():
            a = self.qpos_adr[name]
            qpos[a : a + 7] = (*pose.position, *pose.quat)
        return qpos

    def object_of_geom(self, geom_id: int) -> str | None:
        """The object owning a geom, or None (table, floor, robot)."""
        return self.body_objects.get(int(self.model.geom_bodyid[geom_id]))


def _add_environment(spec: mujoco.MjSpec, scene: Scene) -> None:
    table = scene.table.body.box
    lo, hi = np.asarray(table.min), np.asarray(table.max)
    spec.worldbody.add_geom(
        name=TABLE_GEOM,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=((hi - lo) / 2).tolist(),
        pos=((hi + lo) / 2).tolist(),
        rgba=[0.93, 0.9, 0.84, 1.0],
        solref=list(SOLREF),
        solimp=list(SOLIMP),
        friction=[friction_of(scene.table.material), TORSIONAL, ROLLING],
    )
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[3, 3, 0.1],
        pos=[0, 0, FLOOR_Z],
        rgba=[0.35, 0.37, 0.4, 1.0],
    )
    spec.worldbody.add_light(
        name="sun",
        pos=[0.4, 0.0, 2.5],
        dir=[0.0, 0.0, -1.0],
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        castshadow=False,
        diffuse=[0.7, 0.7, 0.7],
    )
    quat = np.zeros(4)  # camera axes: x = world +y, y = up-and-back; looks at the table
    mujoco.mju_mat2Quat(
        quat, np.array([[0.0, -0.6, 0.8], [1.0, 0.0, 0.0], [0.0, 0.8, 0.6]]).ravel()
    )
    spec.worldbody.add_camera(name="overview", pos=[1.55, 0.0, 1.05], quat=quat.tolist())
    add_scene_cameras(spec)


def build_world_spec(
    scene: Scene,
    *,
    rng: np.random.Generator | None = None,
    pos_noise: float = 0.003,
    yaw_noise_deg: float = 2.0,
    timestep: float = 0.002,
    sleep: bool = False,
    poses: Mapping[str, Pose] | None = None,
    appearance: Mapping[str, Appearance] | None = None,
) -> tuple[mujoco.MjSpec, WorldInfo]:
    """The world as an uncompiled `MjSpec` (attach the robot to it), and its `WorldInfo`.

    `sleep` turns on MuJoCo's sleeping islands (module docstring). The objects start at
    `poses` if given (e.g. a `WorldInfo`'s, to rebuild that world exactly), else at the
    scene's declared poses with noise drawn from `rng`; likewise each object's colour and
    finish (`appearance`, else drawn from a child of `rng`: `utamp_gym.sim.appearance`)."""
    if timestep <= 0 or pos_noise < 0 or yaw_noise_deg < 0:
        raise SimulationError(
            f"need timestep > 0 and noise >= 0 (got {timestep}, {pos_noise}, {yaw_noise_deg})"
        )
    spec = mujoco.MjSpec()
    spec.modelname = scene.name.replace("/", "-")
    spec.compiler.alignfree = False  # body frame == object frame
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10.0
    if sleep:
        spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        spec.option.sleep_tolerance = SLEEP_TOLERANCE
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    _add_environment(spec, scene)
    if poses is None:
        poses = initial_poses(scene, rng, pos_noise, yaw_noise_deg)
    if appearance is None:  # a child generator: the draws above are unchanged
        appearance = object_appearance(scene, rng)
    add_materials(spec, dict(appearance))
    looks = appearance
    geoms = {
        o.name: add_object_body(
            spec,
            scene,
            o.name,
            poses[o.name],
            looks[o.name].rgba,
            material=material_name(o.name),
            accent_material=ACCENT_MATERIAL,
        )
        for o in scene.objects
    }
    info = WorldInfo(
        scene=scene,
        poses=poses,
        body_names={o.name: BODY_PREFIX + o.name for o in scene.objects},
        geom_names=geoms,
        slot_positions={s.name: np.array([*s.position, 0.0]) for s in scene.slots},
        appearance=dict(looks),
    )
    return spec, info


def compile_world(spec: mujoco.MjSpec, info: WorldInfo) -> World:
    """Compile a spec from `build_world_spec` (possibly with a robot attached)."""
    try:
        model = spec.compile()
    except ValueError as exc:
        raise SimulationError(
            f"cannot compile the world of scene '{info.scene.name}': {exc}"
        ) from exc
    body_ids = {n: model.body(b).id for n, b in info.body_names.items()}
    joints = {n: model.body_jntadr[b] for n, b in body_ids.items()}
    return World(
        model=model,
        spec=spec,
        info=info,
        body_ids=body_ids,
        qpos_adr={n: int(model.jnt_qposadr[j]) for n, j in joints.items()},
        dof_adr={n: int(model.jnt_dofadr[j]) for n, j in joints.items()},
        geom_ids={n: [model.geom(g).id for g in gs] for n, gs in info.geom_names.items()},
        slot_positions=info.slot_positions,
        table_geom_id=model.geom(info.table_geom).id,
        body_objects={b: n for n, b in body_ids.items()},
    )


def build_world(
    scene: Scene,
    *,
    rng: np.random.Generator | None = None,
    pos_noise: float = 0.003,
    yaw_noise_deg: float = 2.0,
    timestep: float = 0.002,
) -> World:
    """Build and compile the world of `scene` (no robot)."""
    spec, info = build_world_spec(
        scene, rng=rng, pos_noise=pos_noise, yaw_noise_deg=yaw_noise_deg, timestep=timestep
    )
    return compile_world(spec, info)


# ------------------------------------------------------------------ simulation queries
def settle(model: mujoco.MjModel, data: mujoco.MjData, seconds: float) -> None:
    """Step the simulation for `seconds` of simulated time (controls unchanged)."""
    n = round(seconds / model.opt.timestep)
    if n > 0:
        mujoco.mj_step(model, data, nstep=n)


def _body(model: mujoco.MjModel, name: str) -> int:
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, BODY_PREFIX + name)
    if bid < 0:
        names = [model.body(i).name for i in range(model.nbody)]
        raise UnknownNameError(
            "object", name, [n[len(BODY_PREFIX) :] for n in names if n.startswith(BODY_PREFIX)]
        )
    return bid


def object_pose(
    model: mujoco.MjModel, data: mujoco.MjData, name: str
) -> tuple[np.ndarray, np.ndarray]:
    """World position and orientation quaternion (w, x, y, z) of an object's frame."""
    b = _body(model, name)
    return data.xpos[b].copy(), data.xquat[b].copy()


def object_velocity(
    model: mujoco.MjModel, data: mujoco.MjData, name: str
) -> tuple[np.ndarray, np.ndarray]:
    """Linear velocity of the object frame's origin and angular velocity, both in world axes."""
    res = np.zeros(6)
    mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, _body(model, name), res, 0)
    return res[3:].copy(), res[:3].copy()


def object_orientation(model: mujoco.MjModel, data: mujoco.MjData, name: str) -> str | None:
    """Return "upright"/"inverted" (z axis within TILT_DEG of world ±z), else None (tipped)."""
    up = data.xmat[_body(model, name)].reshape(3, 3)[2, 2]
    limit = math.cos(math.radians(TILT_DEG))
    return "upright" if up >= limit else "inverted" if up <= -limit else None


def sleeping_objects(world: World, data: mujoco.MjData) -> set[str]:
    """Names of the objects MuJoCo has put to sleep (`build_world_spec`'s `sleep`)."""
    tree = world.model.body_treeid
    return {n for n, b in world.body_ids.items() if data.tree_asleep[tree[b]] >= 0}


def _extent(world: World, data: mujoco.MjData, name: str) -> tuple[float, float] | None:
    """World z of an object's bounding-box bottom and top; None if it has tipped over."""
    orientation = object_orientation(world.model, data, name)
    if orientation is None:
        return None
    box = world.scene.type_of(name).bbox
    z = float(data.xpos[world.body_ids[name]][2])
    if orientation == "upright":
        return z + box.min[2], z + box.max[2]
    return z - box.max[2], z - box.min[2]


def rests_on_top(
    world: World, data: mujoco.MjData, name: str, support: str | None, *, tol: float = 0.01
) -> bool:
    """True if `name` stands (upright or inverted) on the top face of `support`.

    `support` is an object, a slot or ``"table"`` (as given by `stack_from_poses`); an
    object that rests *inside* its support (a shaker in an upright mug) is not on top.
    """
    own = _extent(world, data, name)
    if own is None or support is None:
        return False
    if support in world.body_ids:
        orientation = object_orientation(world.model, data, support)
        if orientation is None:
            return False
        t = world.scene.type_of(support)
        z = float(data.xpos[world.body_ids[support]][2])
        # the up-facing part's usable surface (a tray's floor lies below its rim)
        top = (
            z + t.surface_height("on")
            if orientation == "upright"
            else z - t.surface_height("under")
        )
    else:
        top = 0.0
    return abs(own[0] - top) <= tol


def _support_forces(world: World, data: mujoco.MjData) -> dict[str, dict[str, float]]:
    """Per object: upward contact force (N) from each object, "table", "floor" or "other".

    `data` must be forwarded (its contacts and constraint forces current).
    """
    model, d = world.model, data
    body_obj = world.body_objects
    out: dict[str, dict[str, float]] = {n: {} for n in world.body_ids}
    force = np.zeros(6)

    def label(geom: int) -> str:
        if geom == world.table_geom_id:
            return "table"
        obj = body_obj.get(int(model.geom_bodyid[geom]))
        return obj if obj is not None else "floor" if model.geom_bodyid[geom] == 0 else "other"

    for i in range(d.ncon):
        c = d.contact[i]
        if c.efc_address < 0:
            continue
        mujoco.mj_contactForce(model, d, i, force)
        fz = float(c.frame.reshape(3, 3)[:, 2] @ force[:3])  # world z of the force on geom2
        a, b = label(c.geom[0]), label(c.geom[1])
        if b in out:
            out[b][a] = out[b].get(a, 0.0) + fz
        if a in out:
            out[a][b] = out[a].get(b, 0.0) - fz
    return out


def forwarded_copy(
    model: mujoco.MjModel, data: mujoco.MjData, scratch: mujoco.MjData | None = None
) -> mujoco.MjData:
    """A forwarded copy of `data`'s state (contacts and forces current); `data` is untouched.

    `scratch`, an `MjData` of the same model that is never stepped, is overwritten and
    returned instead of allocating a new one. The copy's bodies are all awake: a copy of
    `data` itself would keep its sleeping islands asleep, and their contacts uncomputed.
    """
    if scratch is None:
        scratch = mujoco.MjData(model)
    scratch.time = data.time
    for name in ("qpos", "qvel", "act", "ctrl", "qacc_warmstart", "xfrc_applied"):
        getattr(scratch, name)[:] = getattr(data, name)
    mujoco.mj_forward(model, scratch)
    return scratch


def stack_from_poses(
    world: World,
    data: mujoco.MjData,
    *,
    min_share: float = 0.3,
    scratch: mujoco.MjData | None = None,
) -> dict[str, str | None]:
    """What each object rests on: an object, the slot under it (table), or None.

    The support is whatever pushes the object up hardest (contacts recomputed on a
    `forwarded_copy` of `data`, in `scratch` if given); it must carry at least `min_share`
    of the object's own weight. Resting on the table outside every slot gives ``"table"``;
    on the floor, held by the robot or in the air gives None. Use `rests_on_top` to tell
    *on* from *inside* (shaker in a mug).
    """
    data = forwarded_copy(world.model, data, scratch)
    forces = _support_forces(world, data)
    out: dict[str, str | None] = {}
    for name, by_support in forces.items():
        weight = world.model.body_mass[world.body_ids[name]] * GRAVITY
        best = max(by_support.items(), key=lambda kv: kv[1], default=None)
        if best is None or best[1] < min_share * weight or best[0] in ("floor", "other"):
            out[name] = None
        elif best[0] == "table":
            xy = data.xpos[world.body_ids[name]][:2]
            slots = [
                s.name
                for s in world.scene.slots
                if all(s.region.min[i] - 1e-6 <= xy[i] <= s.region.max[i] + 1e-6 for i in (0, 1))
            ]
            out[name] = slots[0] if slots else "table"
        else:
            out[name] = best[0]
    return out


__all__ = [
    "World",
    "WorldInfo",
    "build_world",
    "build_world_spec",
    "compile_world",
    "forwarded_copy",
    "initial_poses",
    "object_orientation",
    "object_pose",
    "object_velocity",
    "rests_on_top",
    "settle",
    "sleeping_objects",
    "stack_from_poses",
]
