"""The low-level control track on dm_control: the same kitchen, commanded joint by joint.

The macro-action envs (`utamp_gym.env`) step one U-TAMP-2 action at a time; this track is
what dm_control and robosuite users expect instead: a `dm_control.rl.control.Environment`
over the same MuJoCo model (`KitchenPhysics`), whose actions are the Panda's 7 joint-position
targets and the gripper command at 50 Hz and whose reward follows tower progress
(`StackTask` documents spaces, reward and episodes)::

    from dm_control import viewer
    from utamp_gym import dm

    env = dm.load(scene="pick-place/000", seed=0)
    viewer.launch(env)                        # needs a display

`record_plan` records the servo commands the physics executor sends for a macro plan and
`ReplayPolicy` replays them through this interface. `DmEnvAdapter` (`adapter`) is the other
way round: a macro-action Gymnasium env as a `dm_env.Environment`. Needs the ``dm`` extra
(``pip install 'utamp-gym[dm]'``); ``import utamp_gym`` never imports dm_control.
"""

from __future__ import annotations

from utamp_gym.extras import MissingExtraError
from utamp_gym.sim.gl import ensure_gl

try:
    # dm_control fixes its OpenGL (backend and PyOpenGL platform) when it is imported: settle
    # the backend first, so its cameras render on a headless machine (`utamp_gym.sim.gl`)
    ensure_gl()
    from dm_control.rl import control
except ImportError as exc:  # pragma: no cover - depends on the installed extras
    raise MissingExtraError("utamp_gym.dm", "dm", "dm_control", str(exc)) from exc

from utamp_gym.dm.adapter import DmEnvAdapter
from utamp_gym.dm.physics import KitchenPhysics
from utamp_gym.dm.replay import JointTrajectory, ReplayPolicy, record_plan
from utamp_gym.dm.task import CONTROL_TIMESTEP, StackTask
from utamp_gym.suites import resolve_scene
from utamp_gym.symbolic.universe import UniverseKey, ground_universe

DEFAULT_TIME_LIMIT = 120.0  # s of simulated time per episode


def load(
    scene: str = "kitchen-demo",
    seed: int | None = None,
    *,
    time_limit: float = DEFAULT_TIME_LIMIT,
    pos_noise: float = 0.003,
    yaw_noise_deg: float = 2.0,
    settle_s: float = 0.5,
) -> control.Environment:
    """A dm_control Environment of `scene` (suite name, packaged scene or scene file).

    `seed` seeds the task's random state (initial object noise); equal seeds give identical
    episodes. The ``symbolic`` observation lists the fluent atoms of the scene's ground
    U-TAMP-2 problem (`StackTask.atoms`). Episodes last at most `time_limit` s.
    """
    resolved = resolve_scene(scene)
    universe = ground_universe(UniverseKey("utamp2", "gt", None, (scene,)))
    physics = KitchenPhysics.build(resolved)
    task = StackTask(
        resolved,
        universe.fluent_atoms,
        pos_noise=pos_noise,
        yaw_noise_deg=yaw_noise_deg,
        settle_s=settle_s,
        random=seed,
    )
    return control.Environment(
        physics,
        task,
        time_limit=time_limit,
        control_timestep=CONTROL_TIMESTEP,
        legacy_step=False,
    )


__all__ = [
    "CONTROL_TIMESTEP",
    "DmEnvAdapter",
    "JointTrajectory",
    "KitchenPhysics",
    "ReplayPolicy",
    "StackTask",
    "load",
    "record_plan",
]
