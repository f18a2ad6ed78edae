"""The symbolic backend's look (`Surveying`): `utamp2-perceived` in symbolic grounding sees
the episode's initial world through the env's own backend, the world the physics env of the
same world seed starts from."""

from __future__ import annotations

import numpy as np
import pytest

from utamp_gym.backend import DEFAULT_BACKEND, Surveying, backend_factory
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.symbolic_backend import NoWorldToLook
from utamp_gym.planning.methods import plan_scene
from utamp_gym.suites import resolve_scene

SCENE = "pick-place/013"


def test_the_symbolic_look_is_the_physics_world_of_the_same_seed() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=SCENE, masks="none")
    sim = backend_factory(DEFAULT_BACKEND)()
    try:
        env.reset(seed=0, options={"world_seed": 1234})
        backend = env.unwrapped.backend
        assert isinstance(backend, Surveying)
        seen = backend.survey()
        sim.reset(resolve_scene(SCENE), np.random.default_rng(1234))
        truth = sim.survey()  # type: ignore[attr-defined]
        assert [v.camera for v in seen.views] == [v.camera for v in truth.views]
        for a, b in zip(seen.views, truth.views, strict=True):
            np.testing.assert_array_equal(a.depth, b.depth)
            np.testing.assert_array_equal(a.instances, b.instances)
        assert dict(backend.cameras.instances) == dict(sim.cameras.instances)  # type: ignore[attr-defined]
        env.reset(seed=0, options={"world_seed": 99})  # another world: another look
        other = backend.survey().views[0].depth
        assert not np.array_equal(other, seen.views[0].depth)
    finally:
        sim.close()
        env.close()


def test_the_symbolic_look_needs_the_world_seed() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=SCENE, masks="none")
    try:
        env.reset(seed=0)
        with pytest.raises(NoWorldToLook, match="world_seed"):
            env.unwrapped.backend.survey()
        with pytest.raises(NoWorldToLook, match="world_seed"):
            env.unwrapped.backend.cameras  # noqa: B018
    finally:
        env.close()


def test_the_symbolic_look_shows_the_initial_world_after_acting() -> None:
    """Nothing is simulated, and the attributes a look perceives do not change as objects
    move: after actions the look still shows the episode's initial arrangement."""
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", scene=SCENE, masks="none")
    try:
        env.reset(seed=0, options={"world_seed": 1})
        backend = env.unwrapped.backend
        before = backend.survey()
        poses = dict(backend.object_poses())
        plan = plan_scene(resolve_scene(SCENE), "utamp2-gt").plan
        for step in plan[:2]:
            _, _, _, _, info = env.step(env.unwrapped.universe.index(step))
            assert info["failure_reason"] == ""
        moved = backend.object_poses()
        assert any(not np.array_equal(poses[n], moved[n]) for n in poses)  # it acted
        after = backend.survey()
        for a, b in zip(before.views, after.views, strict=True):
            np.testing.assert_array_equal(a.depth, b.depth)
            np.testing.assert_array_equal(a.instances, b.instances)
        assert isinstance(backend, Surveying)
    finally:
        env.close()
