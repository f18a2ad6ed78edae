"""Objects beyond the paper: the extra catalogue, its derived affordances and the suite `extra`."""

from __future__ import annotations

import pytest

from utamp_gym.affordances.rules import derive_affordances
from utamp_gym.cli import main
from utamp_gym.planning.methods import plan_scene
from utamp_gym.scene import load_catalogue, scene_from_dict, scene_to_dict
from utamp_gym.scene.model import STANDING_PART
from utamp_gym.suites import SUITES, resolve_scene, suite_scenes, suite_stats
from utamp_gym.suites.generate import EXTRA_MOVABLES, extra_catalogue, suite_facts

NEW = {name for name, _ in EXTRA_MOVABLES}


@pytest.fixture(scope="module")
def facts() -> frozenset[tuple[str, ...]]:
    return derive_affordances([*load_catalogue().types.values(), *extra_catalogue().types.values()])


def _grasps(facts: frozenset[tuple[str, ...]], t: str) -> set[tuple[str, ...]]:
    return {f[2:] for f in facts if f[0] == "canGraspFrom" and f[1] == t}


def _carries(facts: frozenset[tuple[str, ...]], t: str, part: str = "on") -> set[str]:
    """Types that stand upright on `part` of `t`."""
    return {f[4] for f in facts if f[0] == "isP2PSupportive" and f[1:4] == (part, t, "under")}


def test_six_new_types_of_different_families_with_attributes_only() -> None:
    cat = extra_catalogue()
    assert len(cat.types) >= 6 and not set(cat.types) & set(load_catalogue().types)
    shapes = {n: (t.body.geom, t.parts["on"].shape) for n, t in cat.types.items()}
    assert shapes == {
        "soup-bowl": ("cylinder", "open"),
        "deep-plate": ("cylinder", "flat"),
        "tea-box": ("box", "flat"),
        "oil-bottle": ("cylinder", "pointy"),
        "stock-pot": ("cylinder", "open"),
        "wooden-spatula": ("box", "thin"),
    }
    assert sum(m.kind == "handle" for m in cat["stock-pot"].members.values()) == 2


def test_rules_derive_the_new_objects_affordances(facts) -> None:
    # rim grasps from above only: the floor covers the rim of an upside-down bowl
    assert _grasps(facts, "soup-bowl") == {
        ("rim-front", "on", "front", "back"),
        ("rim-back", "on", "front", "back"),
    }
    assert _carries(facts, "soup-bowl") == set()  # an open top carries nothing
    # a bottle is held by its neck, which stands over its body
    assert {g[0] for g in _grasps(facts, "oil-bottle")} == {"neck"}
    assert ("isSupportable", "oil-bottle", "on") not in facts
    # the plate's well is round: the tea box's diagonal (16.4 cm) does not fit its 16 cm
    assert _carries(facts, "deep-plate") == {"salt-shaker", "glass-mug", "soup-bowl"}
    assert ("isSupportable", "deep-plate", "on") not in facts  # food surface: never face-down
    assert ("isP2PSupportive", "on", "frying-pan", "under", "deep-plate") in facts  # spans it
    assert ("isP2PSupportive", "on", "cutting-board", "under", "tea-box") in facts
    # the upside-down pot is a pedestal; grasped by a lug in either orientation
    assert {"soup-bowl", "oil-bottle", "glass-mug"} <= _carries(facts, "stock-pot", "under")
    assert {g[1] for g in _grasps(facts, "stock-pot")} == {"on", "under"}
    assert ("canLift", "stock-pot", "handle-left") in facts
    # the long spatula lies only on the tray (and the table) and carries nothing
    assert {f[2] for f in facts if f[0] == "isP2PSupportive" and f[4] == "wooden-spatula"} == {
        "wooden-tray",
        "kitchen-table",
    }
    assert not _carries(facts, "wooden-spatula")


def test_suite_extra_is_registered_and_stable() -> None:
    assert "extra" in SUITES
    stats = suite_stats("extra")
    assert (stats.enumerated, stats.trivial, stats.unachievable, stats.kept) == (252, 27, 141, 84)
    assert stats.kept_by_n == {2: 8, 3: 76}
    scenes = suite_scenes("extra")
    assert [s.name for s in scenes[:2]] == ["extra/000", "extra/001"]
    assert resolve_scene("extra/007").name == "extra/007"
    for scene in scenes:
        assert scene.object("tray").on == "slot1"
        assert set(scene.object_names) & NEW, scene.name
        for name in scene.object_names:
            assert scene.in_workspace(scene.world_box(name)), (scene.name, name)
    used = {scene.type_of(o).name for scene in scenes for o in scene.object_names}
    assert set(extra_catalogue().types) <= used  # every new object appears


def test_orientations_are_only_those_the_hand_can_pick_from() -> None:
    facts = suite_facts("extra")
    for scene in suite_scenes("extra"):
        for o in scene.objects:
            t = scene.type_of(o.name).name
            assert ("isSupportable", t, STANDING_PART[o.orientation]) in facts
    inverted = {
        o.type for s in suite_scenes("extra") for o in s.objects if o.orientation != "upright"
    }
    assert "soup-bowl" not in inverted and {"stock-pot", "tea-box"} <= inverted


def test_extra_scenes_export_complete_scene_files() -> None:
    for scene in suite_scenes("extra")[::9]:
        data = scene_to_dict(scene)
        assert set(data["types"]) == {
            scene.type_of(n).name for n in scene.object_names if scene.type_of(n).name in
            extra_catalogue().types
        }  # fmt: skip
        again = scene_from_dict(data)  # the default catalogue does not know the new types
        assert again.poses == scene.poses and again.stacks == scene.stacks


def test_cli_lists_the_extra_suite(capsys) -> None:
    assert main(["scenes", "list", "--suite", "extra"]) == 0
    lines = capsys.readouterr().out.split()
    assert len(lines) == 84 and lines[7] == "extra/007"


def test_the_rules_plan_every_extra_scene() -> None:
    """Every scene the rules call solvable is planned: here every scene of the suite."""
    for scene in suite_scenes("extra"):
        outcome = plan_scene(scene, "utamp2-rules")
        assert outcome.solved, (scene.name, outcome.reason)
        assert outcome.affordance_scores.f1 == 1.0  # the rules are the truth for new types


@pytest.mark.physics
@pytest.mark.parametrize(
    "name",
    [
        "extra/001",  # bowl by its rim onto the tray
        "extra/016",  # plate off the tray, board on, plate on the board
        "extra/036",  # bottle by its neck onto the upside-down pot
        "extra/005",  # the long spatula
    ],
)
def test_new_objects_stack_in_physics(name: str) -> None:
    from utamp_gym.agents.runs import run_episode

    scene = resolve_scene(name)
    result = run_episode(scene, "utamp2-rules", seed=0)
    assert result.success, result.failure
    assert sorted(result.final_stack) == sorted(set(scene.object_names) - {"tray"})
