"""The low-level control track (`utamp_gym.dm`): dm_control Environment, replay, viewer.

Assertions are about what the physics did: the replayed servo commands stack the board on
the tray (perceived from contacts), the viewer's window shows the scene.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import unittest
import warnings

import numpy as np
import pytest
from procs import user_env
from xvfb import virtual_display, wait_until

pytestmark = pytest.mark.physics


pytest.importorskip("dm_control", reason="the dm extra (dm-control) is not installed")
import dm_env  # noqa: E402  (dm_control's dependency)
from dm_env import test_utils  # noqa: E402

from utamp_gym import dm  # noqa: E402  (with dm_control installed it must import)
from utamp_gym.planning.methods import plan_scene  # noqa: E402
from utamp_gym.robot.kinematics import HOME_Q  # noqa: E402
from utamp_gym.suites import resolve_scene  # noqa: E402

SCENE = "pick-place/000"  # the board in slot2 and the tray: two objects


def _hold(time_step: dm_env.TimeStep) -> np.ndarray:
    """Keep the arm where it is, fingers open."""
    return np.concatenate([time_step.observation["arm_qpos"], [0.08]])


def test_load_specs_and_first_observation() -> None:
    env = dm.load(scene=SCENE, seed=0)
    spec = env.action_spec()
    assert spec.shape == (8,)
    assert spec.minimum[7] == 0.0 and spec.maximum[7] == pytest.approx(0.08)
    assert np.all(spec.minimum[:7] < HOME_Q) and np.all(spec.maximum[:7] > HOME_Q)
    assert env.control_timestep() == pytest.approx(dm.CONTROL_TIMESTEP)
    ts = env.reset()
    assert ts.first()
    obs = ts.observation
    for name, s in env.observation_spec().items():
        s.validate(obs[name])
    atoms = dict(zip(env.task.atoms, obs["symbolic"], strict=True))
    assert atoms["(oc in hand air)"] == 1
    assert atoms["(oc under board slot2)"] == 1 and atoms["(oc on slot2 board)"] == 1
    assert atoms["(oc in hand board)"] == 0
    assert obs["tower_height"][0] == 0.0
    assert obs["gripper_gap"][0] == pytest.approx(0.08, abs=1e-3)
    scene = resolve_scene(SCENE)
    board = [o.name for o in scene.objects].index("board")
    assert np.allclose(obs["object_poses"][board][:2], scene.poses["board"].position[:2], atol=0.01)
    ts = env.step(_hold(ts))
    assert ts.mid() and ts.reward == 0.0 and ts.discount == 1.0


def test_equal_seeds_give_equal_episodes_and_noise_differs() -> None:
    first = [dm.load(scene=SCENE, seed=s).reset().observation for s in (3, 3, 4)]
    assert np.array_equal(first[0]["object_poses"], first[1]["object_poses"])
    assert not np.array_equal(first[0]["object_poses"], first[2]["object_poses"])


def test_bad_actions_raise_value_error() -> None:
    env = dm.load(scene=SCENE, seed=0)
    env.reset()
    with pytest.raises(ValueError, match="8 finite numbers"):
        env.step(np.zeros(7))
    with pytest.raises(ValueError, match="8 finite numbers"):
        env.step(np.full(8, np.nan))


def test_scripted_replay_of_a_macro_plan_solves_a_two_object_scene() -> None:
    outcome = plan_scene(resolve_scene(SCENE), "utamp2-gt")
    assert outcome.solved and len(outcome.plan) == 2
    trajectory = dm.record_plan(SCENE, outcome.plan)
    policy = dm.ReplayPolicy(trajectory, dm.CONTROL_TIMESTEP)
    env = dm.load(scene=SCENE, seed=0, pos_noise=0.0, yaw_noise_deg=0.0)
    ts = env.reset()
    rewards, held = [], False
    while not ts.last():
        ts = env.step(policy(ts))
        rewards.append(ts.reward)
        atoms = dict(zip(env.task.atoms, ts.observation["symbolic"], strict=True))
        held = held or atoms["(oc in hand board)"] == 1
    assert held, "the hand never perceived the board in it (the grasp is measured)"
    assert ts.discount == 0.0 and ts.reward == 1.0  # ended at the goal, not the time limit
    assert env.physics.data.time < trajectory.duration + 1.0
    perception = env.task.perception(env.physics)
    assert perception.tower("tray") == ["board"] and perception.anomalies == {}
    assert rewards[0] == 0.0 and max(rewards[:-1], default=0.0) < 1.0
    assert env.physics.gripper_gap() > 0.03  # released


def test_replay_without_the_plan_does_not_solve() -> None:
    """Holding still never stacks anything: the reward comes from the physics."""
    env = dm.load(scene=SCENE, seed=0, time_limit=1.0)
    ts = env.reset()
    while not ts.last():
        ts = env.step(_hold(ts))
    assert ts.reward == 0.0 and ts.discount == 1.0  # truncated by the time limit


def test_viewer_runtime_runs_headless() -> None:
    """The part of `dm_control.viewer.launch` that drives the env, without a window."""
    with warnings.catch_warnings():  # importing the viewer warns that there is no display
        warnings.simplefilter("ignore")
        from dm_control.viewer import runtime

    env = dm.load(scene=SCENE, seed=0)
    errors: list[str] = []
    rt = runtime.Runtime(environment=env, policy=_hold)
    rt.on_error += errors.append
    rt.tick(0.0, paused=False)
    start = env.physics.data.time
    rt.tick(0.2, paused=False)
    assert errors == [] and rt.state == runtime.State.RUNNING
    assert env.physics.data.time == pytest.approx(start + 0.2, abs=dm.CONTROL_TIMESTEP)


LAUNCH = textwrap.dedent(
    """
    import numpy as np
    from dm_control import viewer
    from utamp_gym import dm

    env = dm.load(scene="pick-place/000", seed=0)
    policy = lambda ts: np.concatenate([ts.observation["arm_qpos"], [0.08]])
    viewer.launch(env, policy=policy, width=800, height=600)
    """
)


def test_cameras_render_headless_without_mujoco_gl() -> None:
    """dm_control reads MUJOCO_GL when it is imported (unset: GLFW, which needs a display);
    `KitchenPhysics` renders on the backend `utamp_gym.sim.gl` picks instead."""
    code = """
        from utamp_gym import dm

        env = dm.load("pick-place/000", seed=0)
        env.reset()
        frame = env.physics.render(120, 160, camera_id="overview")
        print(frame.shape, frame.dtype, float(frame.std()) > 10)
    """
    run = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=user_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "(120, 160, 3) uint8 True"


def test_dm_control_viewer_launch_shows_the_scene_under_xvfb() -> None:
    with virtual_display() as display:
        proc = subprocess.Popen(
            [sys.executable, "-c", LAUNCH],
            env=display.env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        try:

            def table_visible() -> bool:
                img = display.screenshot().astype(int)
                return float((img.min(axis=-1) > 200).mean()) > 0.05  # the white table top

            wait_until(lambda: table_visible() or proc.poll() is not None, 180, "the viewer")
            assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
            r, g, b = np.moveaxis(display.screenshot().astype(int), -1, 0)
            tray = (r > 150) & (r - g > 40) & (g - b > 20)  # the wooden tray's orange-brown
            assert float(tray.mean()) > 0.001
        finally:
            proc.kill()
            proc.wait()


class StackTaskContractTest(test_utils.EnvironmentTestMixin, unittest.TestCase):
    """dm_env's own interface checks; a short time limit ends episodes (LAST, auto-reset)."""

    def make_object_under_test(self) -> dm_env.Environment:
        return dm.load(scene=SCENE, seed=0, time_limit=0.2)

    def make_action_sequence(self):  # type: ignore[no-untyped-def]
        spec = self.environment.action_spec()
        middle = (spec.minimum + spec.maximum) / 2
        for _ in range(25):
            yield middle
