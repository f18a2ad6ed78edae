"""Tracing an invalid plan's false facts back to the perceived reading that granted them."""

from __future__ import annotations

import pytest

from utamp_gym.methods.blame import blame_plan, with_declared
from utamp_gym.methods.perceived import build_perceived_scene
from utamp_gym.suites import resolve_scene

SCENE = "procedural-v1/train/0168"  # a tray (base) too heavy to lift by its edges
PICK = "(pick-support base base-edge-left on left right back on slot1 under on)"


def _perceived(**tray: float):  # type: ignore[no-untyped-def]
    scene = resolve_scene(SCENE)
    types = {o.name: scene.type_of(o.name) for o in scene.objects}
    types["base"] = types["base"]._replace(**tray)
    return scene, build_perceived_scene(scene, types)


def test_a_false_fact_from_a_light_mass_reading_is_blamed_on_the_mass() -> None:
    scene, ps = _perceived(mass=0.4)
    (false,) = blame_plan(scene, ps, [PICK])
    assert (false.step, false.origin, false.objects) == (0, "mass", ("base",))
    assert false.fact.startswith("(canGraspFrom base base-edge-left")
    assert (false.predicate, false.member) == ("canGraspFrom", "edge")


def test_a_false_fact_the_likely_readings_deny_came_from_an_alternative() -> None:
    scene, ps = _perceived()  # every reading right: only a hoped alternative grants it
    (false,) = blame_plan(scene, ps, [PICK])
    assert (false.origin, false.objects) == ("alternative", ())


def test_a_valid_plan_has_nothing_to_blame() -> None:
    scene, ps = _perceived(mass=0.4)
    assert blame_plan(scene, ps, []) == ()


def test_an_unknown_source_names_the_valid_ones() -> None:
    t = resolve_scene(SCENE).type_of("base")
    with pytest.raises(ValueError, match="mass, material, members, parts, geometry"):
        with_declared(t, t, "colour")
