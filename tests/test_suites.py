"""Benchmark suites: deterministic enumeration, achievability, export."""

from __future__ import annotations

import itertools

import pytest

from utamp_gym.affordances.facts import load_ground_truth
from utamp_gym.errors import UnknownNameError
from utamp_gym.scene import scene_from_dict, scene_to_dict
from utamp_gym.suites import get_scene, resolve_scene, suite_scenes, suite_stats
from utamp_gym.suites.generate import _orientations, _supports, tower_achievable


def test_counts_are_stable_and_documented() -> None:
    pp, sl = suite_stats("pick-place"), suite_stats("sliding")
    assert (pp.enumerated, pp.trivial, pp.unachievable, pp.kept) == (177, 15, 56, 106)
    assert pp.kept_by_n == {2: 5, 3: 20, 4: 47, 5: 34}
    assert (sl.enumerated, sl.unachievable, sl.kept) == (58, 16, 42)
    assert [s.name for s in suite_scenes("pick-place")[:2]] == ["pick-place/000", "pick-place/001"]


def test_every_pick_place_scene_is_valid_and_in_the_workspace() -> None:
    for scene in suite_scenes("pick-place"):
        assert scene.object("tray").on == "slot1"
        assert 2 <= scene.n_objects <= 5
        for name in scene.object_names:
            assert scene.in_workspace(scene.world_box(name)), (scene.name, name)


def test_sliding_scenes_need_the_slide_first() -> None:
    for scene in suite_scenes("sliding"):
        assert scene.stacks["slot1"] == ("tray",)
        assert not scene.in_workspace(scene.world_box("tray"))
        assert scene.in_workspace(scene.world_box("tray", "handle-back"))
        assert scene.spaces and scene.spaces[0].slot == "slot1"


def test_achievability_is_a_combinatorial_check() -> None:
    gt = load_ground_truth()
    tray = ("wooden-tray", "upright")
    pan, board = ("frying-pan", "upright"), ("cutting-board", "upright")
    mug_up, mug_inv = ("glass-mug", "upright"), ("glass-mug", "inverted")
    salt = ("salt-shaker", "upright")
    assert tower_achievable(gt, tray, [pan, board, mug_inv, salt])
    assert not tower_achievable(gt, tray, [pan, mug_up])  # the pan only carries the board
    assert not tower_achievable(gt, tray, [mug_up, salt])  # an open mug top carries nothing
    assert tower_achievable(gt, tray, [mug_inv, salt])


def test_pruned_tower_search_equals_trying_every_order() -> None:
    gt = load_ground_truth()
    tray = ("wooden-tray", "upright")
    types = ("salt-shaker", "glass-mug", "cutting-board", "frying-pan")
    nodes = [(t, o) for t in types for o in _orientations(gt, t)]
    for n in range(1, 5):
        for others in itertools.combinations_with_replacement(nodes, n):
            every_order = any(
                all(_supports(gt, a, b) for a, b in itertools.pairwise((tray, *order)))
                for order in itertools.permutations(others)
            )
            assert tower_achievable(gt, tray, others) == every_order, others


def test_scenes_export_and_reload_identically() -> None:
    for scene in (*suite_scenes("pick-place")[::17], *suite_scenes("sliding")[::11]):
        again = scene_from_dict(scene_to_dict(scene))
        assert again.poses == scene.poses and again.stacks == scene.stacks


def test_lookup_by_name() -> None:
    assert get_scene("sliding/003").name == "sliding/003"
    assert resolve_scene("kitchen-demo").n_objects == 5
    with pytest.raises(UnknownNameError, match=r"\(pick-place has pick-place/000 to 105\)"):
        resolve_scene("pick-place/999")
