"""Per-scene caches are bounded, least recently used out, and a miss changes no rollout."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from utamp_gym.env import object_maps
from utamp_gym.env.registry import register_envs
from utamp_gym.suites import ALL_SUITES, all_scene_names
from utamp_gym.symbolic import scene_cache
from utamp_gym.symbolic.scene_cache import SCENES_KEPT, SceneCache

register_envs()


def test_the_least_recently_used_scene_goes_first() -> None:
    made: list[str] = []
    cache: SceneCache[str] = SceneCache(2)

    def get(name: str) -> str:
        return cache.get(name, lambda: made.append(name) or name.upper())

    assert [get("a"), get("b"), get("a")] == ["A", "B", "A"]
    get("c")  # b was used less recently than a
    assert made == ["a", "b", "c"] and len(cache) == 2
    assert "a" in cache and "b" not in cache
    get("b")
    assert made == ["a", "b", "c", "b"] and "a" not in cache


def test_the_bound_holds_every_packaged_suite_whole() -> None:
    sizes = {suite: len(all_scene_names(suite)) for suite in ALL_SUITES}
    assert max(sizes.values()) <= SCENES_KEPT, sizes


@pytest.mark.parametrize("size", [0, -3])
def test_a_cache_keeps_at_least_one_scene(size: int) -> None:
    with pytest.raises(ValueError, match="at least one scene"):
        SceneCache(size)


def _scene_caches(obj: object, seen: set[int] | None = None) -> list[SceneCache[Any]]:
    """Every SceneCache reachable through the attributes of `obj`."""
    seen = set() if seen is None else seen
    if id(obj) in seen or isinstance(obj, type):
        return []
    seen.add(id(obj))
    if isinstance(obj, SceneCache):
        return [obj]
    return [c for v in getattr(obj, "__dict__", {}).values() for c in _scene_caches(v, seen)]


def _rollout(episodes: int) -> tuple[list[tuple[Any, ...]], list[tuple[int, int]]]:
    """Masked random episodes of the procedural env over `episodes` seeds (a new scene nearly
    every time): everything each step returns (`repr` of info), and each per-scene cache's
    (length, bound) at the end."""
    env = gym.make("UTampKitchenProcedural-v0", grounding="symbolic")
    rng = np.random.default_rng(0)
    out: list[tuple[Any, ...]] = []
    for seed in range(episodes):
        obs, info = env.reset(seed=seed)
        out.append((env.unwrapped.scene.name, repr(info)))
        for _ in range(4):
            action = int(rng.choice(np.flatnonzero(info["action_mask"])))
            obs, reward, terminated, truncated, info = env.step(action)
            flat = b"".join(np.asarray(v).tobytes() for v in obs.values())
            out.append((flat, reward, terminated, truncated, repr(info)))
            if terminated or truncated:
                break
    caches = [(len(c), c.size) for c in _scene_caches(env.unwrapped)]
    assert len(caches) >= 4, "the env's per-scene caches were not found"
    env.close()
    return out, caches


def test_an_env_meeting_new_scenes_keeps_only_the_bound_and_acts_the_same(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    unbounded, kept = _rollout(12)
    assert max(n for n, _ in kept) > 2  # the rollout met more scenes than the bound below
    monkeypatch.setattr(scene_cache, "SCENES_KEPT", 2)
    # the scene maps shared by a process's object interfaces are made anew at the lower bound
    object_maps.shared_maps.cache_clear()
    try:
        bounded, kept = _rollout(12)
    finally:
        object_maps.shared_maps.cache_clear()  # later tests get caches at the packaged bound
    assert all(size == 2 and n <= 2 for n, size in kept)
    assert bounded == unbounded
