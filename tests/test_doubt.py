"""Planning under doubt: uncertain attributes take the value that promises less, unless the goal
then becomes unsolvable (methods/doubt.py, methods/perceived.plan_seen)."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from utamp_gym.affordances.sources import plan_affordances
from utamp_gym.contract.perceiver import PerceivedAttributes
from utamp_gym.methods.doubt import DOUBT_THRESHOLD, cautious_types, with_value
from utamp_gym.methods.perceived import PerceivedScene, build_perceived_scene, plan_seen
from utamp_gym.scene.model import Scene
from utamp_gym.suites import resolve_scene


def _seen(
    name: str, obj: str, attribute: str, p: float, alts: tuple[Any, ...]
) -> tuple[Scene, PerceivedScene]:
    """The declared scene perceived exactly, with one attribute reported at confidence `p`."""
    scene = resolve_scene(name)
    ps = build_perceived_scene(scene, {o.name: scene.type_of(o.name) for o in scene.objects})
    report = PerceivedAttributes(ps.types[obj], {attribute: p}, {attribute: alts})
    return scene, dataclasses.replace(ps, reports={obj: report})


def test_with_value() -> None:
    t = resolve_scene("pick-place/000").type_of("board")
    assert with_value(t, "mass", "2.5").mass == 2.5
    assert with_value(t, "robustness", "fragile").robustness == "fragile"
    assert with_value(t, "mass", "heavy") is None
    assert with_value(t, "members", ("handle",)) is None  # only a whole type replaces geometry
    other = resolve_scene("pick-place/000").type_of("tray")
    assert with_value(t, "members", other) == other._replace(name=t.name)


@pytest.mark.parametrize(
    ("obj", "attribute", "alts", "cautious"),
    [
        ("tray", "robustness", ("solid", "fragile"), "fragile"),  # the least load it carries
        ("pan", "mass", (0.4, 5.0), 5.0),  # the heavier class: lifted by no grasp
    ],
)
def test_doubtful_attribute_takes_the_value_that_promises_less(
    obj: str, attribute: str, alts: tuple[Any, ...], cautious: Any
) -> None:
    _, ps = _seen("pick-place/050", obj, attribute, 0.5, alts)
    types, doubts = cautious_types(ps.planning, ps.types, ps.reports)
    assert [(d.object, d.attribute, d.cautious) for d in doubts] == [(obj, attribute, cautious)]
    assert getattr(types[obj], attribute) == cautious
    name = ps.types[obj].name
    before = {f for f in plan_affordances(ps.planning) if name in f}
    after_scene = build_perceived_scene(ps.declared, types).planning
    after = {f for f in plan_affordances(after_scene) if name in f}
    assert len(after) < len(before)  # fewer facts (a pan too heavy to lift may be slid)
    assert {f[0] for f in before - after} <= {"canLift", "isP2PSupportive", "isSupportive"}


def test_confident_or_alternative_free_attributes_stay() -> None:
    _, ps = _seen("pick-place/050", "tray", "robustness", DOUBT_THRESHOLD, ("fragile",))
    assert cautious_types(ps.planning, ps.types, ps.reports)[1] == ()
    _, ps = _seen("pick-place/050", "tray", "robustness", 0.1, ())
    assert cautious_types(ps.planning, ps.types, ps.reports)[1] == ()
    # an alternative that promises more than the reading is not taken
    _, ps = _seen("pick-place/050", "mug", "robustness", 0.1, ("sturdy",))
    assert cautious_types(ps.planning, ps.types, ps.reports)[1] == ()


def test_plans_cautiously_when_the_goal_stays_solvable() -> None:
    scene, ps = _seen("pick-place/050", "pan", "mass", 0.5, (5.0,))
    outcome, planned = plan_seen(scene, ps)
    assert outcome.solved and not planned.doubt.fell_back
    assert planned.types["pan"].mass == 5.0
    assert "planned under doubt (pan.mass" in planned.doubt.note()
    # a 5 kg pan is never lifted: the plan does not pick it by a grasp that lifts
    assert not any(f[0] == "canLift" and f[1] == "frying-pan" for f in outcome.facts)


def test_falls_back_to_the_likely_value_when_caution_makes_the_goal_unsolvable() -> None:
    scene, ps = _seen("pick-place/000", "tray", "robustness", 0.5, ("fragile",))
    outcome, planned = plan_seen(scene, ps)
    assert outcome.solved  # the 0.6 kg board cannot rest on a fragile tray: caution fails
    assert planned.doubt.fell_back and planned.types["tray"].robustness == "sturdy"
    assert planned.doubt.note().startswith("cautious values unsolvable, planned the likely ones")


def test_certain_reports_plan_as_before() -> None:
    scene = resolve_scene("pick-place/000")
    ps = build_perceived_scene(scene, {o.name: scene.type_of(o.name) for o in scene.objects})
    outcome, planned = plan_seen(scene, ps)
    assert outcome.solved and planned.doubt.doubts == () and planned.doubt.note() == ""
