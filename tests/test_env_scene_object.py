"""The env takes a `Scene` built in code (option ``scene``) as it is: no scene file, and an
action universe and per-scene caches keyed by its content (`Scene.key`), so a scene with a
packaged scene's name but other objects never shares what was derived for that one."""

from __future__ import annotations

import pickle
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import utamp_gym  # noqa: F401  (registers the env ids)
from utamp_gym.agents.runs import execute_plan
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene import io as scene_io
from utamp_gym.scene.io import scene_to_toml
from utamp_gym.scene.model import BuiltScene, Scene, SceneObject
from utamp_gym.suites import resolve_scene
from utamp_gym.symbolic.atoms import InitialAtoms
from utamp_gym.symbolic.universe import ground_universe

NAME = "pick-place/013"  # a pan on the tray, a board on slot2


def _impostor() -> Scene:
    """`NAME`'s table and name, but a board on the tray and a mug on slot2 (no pan)."""
    packaged = resolve_scene(NAME)
    objects = (
        packaged.objects[0],
        SceneObject("board", "cutting-board", "tray"),
        SceneObject("mug", "glass-mug", "slot2"),
    )
    return packaged._replace(objects=objects)


def _env(scene: str | Scene, **options: object) -> UTampKitchenEnv:
    return UTampKitchenEnv(suite="pick-place", scene=scene, grounding="symbolic", **options)  # type: ignore[arg-type]


def _shown(env: UTampKitchenEnv, info: dict) -> set[str]:
    return {env.universe.actions[a] for a in np.flatnonzero(info["action_mask"])}


def test_scene_key_is_the_content_not_the_name() -> None:
    packaged, other = resolve_scene(NAME), _impostor()
    assert other.name == packaged.name and other != packaged
    assert other.key != packaged.key and other.key.startswith(f"{NAME}#")
    assert resolve_scene(NAME).key == packaged.key  # equal content: equal key
    assert BuiltScene(other) == BuiltScene(packaged._replace(objects=other.objects))
    assert BuiltScene(other) != BuiltScene(packaged)


@pytest.mark.parametrize("masks", ["affordances", "none"])
def test_a_code_built_scene_with_a_packaged_name_gets_its_own_universe_and_masks(
    masks: str, tmp_path: Path
) -> None:
    other = _impostor()
    packaged_env, built_env = _env(NAME, masks=masks), _env(other, masks=masks)
    path = tmp_path / "impostor.toml"  # the old route: the same scene through a file
    path.write_text(scene_to_toml(other))
    file_env = UTampKitchenEnv(
        suite="pick-place", scene=str(path), grounding="symbolic", masks=masks
    )
    assert built_env.universe.key != packaged_env.universe.key
    assert built_env.universe.key.scenes == (BuiltScene(other),)
    _, packaged_info = packaged_env.reset(seed=0)
    _, built_info = built_env.reset(seed=0)  # after the packaged scene, in the same process
    _, file_info = file_env.reset(seed=0)
    assert built_env.scene is other and built_info["scene"] == NAME
    assert _shown(built_env, built_info) == _shown(file_env, file_info)
    assert _shown(built_env, built_info) != _shown(packaged_env, packaged_info)
    assert any("mug" in a for a in _shown(built_env, built_info))
    assert not any("pan" in a for a in _shown(built_env, built_info))


def test_the_code_built_scene_is_played_to_its_goal_without_a_scene_file(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    other = _impostor()
    plan = plan_scene(other, "utamp2-gt").plan
    assert any("mug" in step for step in plan)

    def no_file(scene: Scene) -> str:
        raise AssertionError("the scene was written to a file")

    monkeypatch.setattr(scene_io, "scene_to_toml", no_file)
    ex = execute_plan(other, plan, grounding="symbolic")
    assert ex.success and ex.failure is None
    assert ex.final_stack == ["board", "mug"] and "pan" not in ex.object_poses


def test_per_scene_caches_do_not_mix_scenes_of_one_name() -> None:
    packaged, other = resolve_scene(NAME), _impostor()
    env = _env(NAME)
    initial = InitialAtoms(env.universe.domain, "utamp2", "gt", 0.0)
    rng = np.random.default_rng(0)
    first, second = initial(packaged, rng), initial(other, rng)
    assert any(" pan " in a for a in first.static) and not any(" mug " in a for a in first.static)
    assert any(" mug " in a for a in second.static) and not any(" pan " in a for a in second.static)
    assert first.fluent != second.fluent


def test_a_scene_equal_to_the_packaged_one_is_taken_by_its_name() -> None:
    by_name, by_object = _env(NAME), _env(resolve_scene(NAME))
    assert by_object.options.scene == NAME
    assert by_object.universe is by_name.universe  # no universe of its own


def test_gym_make_takes_a_scene_object() -> None:
    other = _impostor()
    env = gym.make("UTampKitchen-v0", scene=other, grounding="symbolic")
    try:
        _, info = env.reset(seed=1)
        assert info["scene"] == NAME and env.unwrapped.scene is other  # type: ignore[attr-defined]
    finally:
        env.close()


def test_pickling_an_env_of_a_code_built_scene_regrounds_it_from_the_scene() -> None:
    other = _impostor()
    env = _env(other)
    _, info = env.reset(seed=2)
    valid = np.flatnonzero(info["action_mask"])
    env.step(int(valid[0]))
    data = pickle.dumps(env)
    ground_universe.cache_clear()  # as in a fresh process: nothing to look the key up in
    clone = pickle.loads(data)
    assert clone.scene == other and clone.universe.key == env.universe.key
    assert clone.universe.actions == env.universe.actions
    _, info = env.reset(seed=5)
    _, clone_info = clone.reset(seed=5)
    np.testing.assert_array_equal(info["action_mask"], clone_info["action_mask"])
    a = int(np.flatnonzero(info["action_mask"])[0])
    obs, reward, *_ = env.step(a)
    clone_obs, clone_reward, *_ = clone.step(a)
    assert reward == clone_reward
    for key in obs:
        np.testing.assert_array_equal(obs[key], clone_obs[key])
