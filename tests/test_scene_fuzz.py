"""Property: a mutated scene or catalogue file loads as a usable model or is a clean `SceneError`.

Hypothesis corrupts valid files (the demo scene, a scene touching every schema field, the
kitchen catalogue): values become wrong types, NaN/inf, negatives, huge integers, strings
for booleans; keys are deleted, added or duplicated; names are swapped (duplicates,
dangling references); tables become scalars and scalars tables; the bytes are truncated,
overwritten or re-encoded. Whatever comes out, loading it either gives a model that the
rest of the package can use (poses, export round trip, affordance rules, PDDL problem) or
raises `SceneError` whose one-line message names the file and, past the TOML syntax, a
well-formed field path. Any other exception fails the test. Derandomized: CI sees the same
examples every run.
"""

from __future__ import annotations

import copy
import math
import re
import tomllib
from collections.abc import Callable, Iterator
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
import tomli_w
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from scene_bases import base_catalogue, base_scene

from utamp_gym.affordances.rules import derive_affordances
from utamp_gym.errors import SceneError
from utamp_gym.resources import asset_path
from utamp_gym.scene import load_catalogue, load_scene, scene_to_dict, scene_to_toml
from utamp_gym.scene.catalogue import Catalogue, parse_type, type_to_dict
from utamp_gym.scene.geometry import SIDES
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.pddl import parse_domain, parse_problem
from utamp_gym.symbolic.pddl_model import Domain
from utamp_gym.symbolic.problem import build_problem, domain_text

_SEGMENT = r'(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*")(?:\[\d+\])*'
FIELD_PATH = re.compile(rf"{_SEGMENT}(?:\.{_SEGMENT})*")
FILE_LEVEL = ("invalid TOML", "not UTF-8 text")
NAME = re.compile(r"[a-z][a-z0-9-]*")  # the names of objects, slots, types and members

BASES: dict[str, Callable[[], dict[str, Any]]] = {
    "demo": lambda: tomllib.loads(asset_path("scenes", "kitchen-demo.toml").read_text("utf-8")),
    "full": base_scene,
    "catalogue": base_catalogue,
}

SPECIAL = [
    math.nan, math.inf, -math.inf, 0, -1, -0.25, 1e-300, 1e9, 10**400, -(10**400), 2**64,
    True, False, "", "false", "true", "0.5", "nan", "Tray", "slot1", "tray", "salt-shaker",
    "kitchen-table", "inverted", "body", "flat", "on", "hand", "a b", "x\ny", "\u00e9",
]  # fmt: skip
scalars = st.one_of(
    st.sampled_from(SPECIAL),
    st.integers(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=10),
)
values = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=3)
    ),
    max_leaves=6,
)


def _slots(node: Any) -> Iterator[tuple[Any, Any]]:
    """Every (container, key) pair of a parsed TOML document, depth first."""
    items = node.items() if isinstance(node, dict) else enumerate(node)
    for k, v in list(items):
        yield node, k
        if isinstance(v, dict | list):
            yield from _slots(v)


def _strings(node: Any) -> list[str]:
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return [*node, *(s for v in node.values() for s in _strings(v))]
    if isinstance(node, list):
        return [s for v in node for s in _strings(v)]
    return []


def _wild_edit(draw: st.DrawFn, data: dict[str, Any], parent: Any, k: Any) -> None:
    """Wrong types, special numbers, deleted/added/duplicated keys, wrapped values."""
    value = parent[k]
    op = draw(st.sampled_from(["replace", "delete", "duplicate", "add-key", "wrap", "scale"]))
    if op == "replace":
        parent[k] = draw(values)
    elif op == "delete":
        del parent[k]
    elif op == "duplicate" and isinstance(parent, list):
        parent.append(copy.deepcopy(value))
    elif op == "duplicate":
        parent[draw(st.text(min_size=1, max_size=8))] = copy.deepcopy(value)
    elif op == "add-key" and isinstance(value, dict):
        value[draw(st.text(max_size=8))] = draw(values)
    elif op == "scale" and isinstance(value, int | float) and not isinstance(value, bool):
        parent[k] = value * draw(st.sampled_from([-1.0, 0.0, 2.0, 1e6]))
    else:
        parent[k] = draw(st.sampled_from([[value], {"value": value}]))


#: keys a valid file may omit
OPTIONAL = {"description", "goal_base", "table", "spaces", "types", "orientation", "position"}
OPTIONAL |= {"rgba", "movable", "kind", "geom", "size", "center", "height", "food_surface"}


def _plausible_edit(draw: st.DrawFn, data: dict[str, Any], parent: Any, k: Any) -> None:
    """Edits a user might make, so that many files stay valid: the other branch is tested."""
    value = parent[k]
    if isinstance(value, bool):
        parent[k] = not value
    elif isinstance(value, int | float):
        parent[k] = value + draw(st.floats(-0.01, 0.01))
    elif isinstance(value, str) and value in ("upright", "inverted"):
        parent[k] = "inverted" if value == "upright" else "upright"
    elif isinstance(value, str):  # duplicate names, dangling or rewired references
        names = [s for s in _strings(data) if NAME.fullmatch(s)]
        parent[k] = draw(st.sampled_from(names or [""]))
    elif isinstance(parent, dict) and k in OPTIONAL:
        del parent[k]


@st.composite
def mutated_file(draw: st.DrawFn) -> tuple[str, bytes]:
    """(base kind, file bytes) after one or two edits of a valid file."""
    kind = draw(st.sampled_from(sorted(BASES)))
    data = BASES[kind]()
    rnd = draw(st.randoms(use_true_random=False))  # a uniform pick of the edited value
    for _ in range(draw(st.integers(1, 2))):
        slots = list(_slots(data))
        if not slots:
            break
        parent, k = rnd.choice(slots)
        edit = draw(st.sampled_from([_wild_edit, _plausible_edit]))
        edit(draw, data, parent, k)
    raw = tomli_w.dumps(data).encode()
    corruption = rnd.choice([None] * 12 + ["truncate", "insert", "overwrite", "utf16"])
    if corruption == "utf16":
        raw = raw.decode().encode("utf-16")
    elif corruption is not None:
        at = draw(st.integers(0, len(raw)))
        junk = draw(st.binary(min_size=1, max_size=4))
        raw = {
            "truncate": raw[:at],
            "insert": raw[:at] + junk + raw[at:],
            "overwrite": raw[:at] + junk + raw[at + len(junk) :],
        }[corruption]
    return kind, raw


def _loaded_or_clean_error(load: Callable[[Path], Any], path: Path) -> Any:
    """The loaded model, or None after checking the `SceneError` is well-formed."""
    try:
        return load(path)
    except SceneError as error:
        message = str(error)
        assert len(message.splitlines()) == 1, message
        assert message.startswith(f"{path}: "), message
        if error.field is None:
            assert message.removeprefix(f"{path}: ").startswith(FILE_LEVEL), message
        else:
            assert FIELD_PATH.fullmatch(error.field), error.field
            assert f"{path}: field '{error.field}': " in message
        return None


def _check_scene(scene: Scene, scratch: Path, kitchen: Catalogue, domain: Domain) -> None:
    """A scene that loads is usable by the rest of the package."""
    for name in scene.object_names:
        box = scene.world_box(name)
        assert all(math.isfinite(v) for v in (*box.min, *box.max))
        assert scene.slot(scene.slot_of(name)).box.contains_xy(box, tol=1e-6)
    again_path = scratch / "again.toml"
    again_path.write_text(scene_to_toml(scene), encoding="utf-8")
    again = load_scene(again_path, catalogue=kitchen)
    assert scene_to_dict(again) == scene_to_dict(scene)
    assert again.poses == scene.poses
    try:
        base = scene.tower_base
    except SceneError as error:
        assert error.field == "goal_base"
        return
    assert base in scene.object_names
    types = {scene.type_of(n).name: scene.type_of(n) for n in scene.object_names}
    problem = build_problem(scene, derive_affordances(types.values()))
    parsed = parse_problem(problem.text, source=scene.name, domain=domain)
    assert set(scene.object_names) <= set(parsed.objects)


def _check_catalogue(catalogue: Catalogue) -> None:
    for t in catalogue.types.values():
        assert parse_type(t.name, type_to_dict(t), "<export>") == t
        for side in SIDES:
            size, centre = t.surface_size(side), t.surface_center(side)
            assert all(math.isfinite(v) and v > 0 for v in size)
            assert all(math.isfinite(v) for v in (*centre, t.surface_height(side)))
    derive_affordances(catalogue.types.values())  # the rules accept whatever loads


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("scene-fuzz")


@pytest.fixture(scope="module")
def kitchen() -> Catalogue:
    return load_catalogue()


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(domain_text("utamp2"))


@settings(
    max_examples=150,
    derandomize=True,
    database=None,
    deadline=timedelta(seconds=5),  # a hang, not a slow machine; the whole test is bounded
    suppress_health_check=[HealthCheck.too_slow],
)
@given(sample=mutated_file())
def test_mutated_file_loads_or_is_a_scene_error_naming_the_field(
    scratch: Path, kitchen: Catalogue, domain: Domain, sample: tuple[str, bytes]
) -> None:
    kind, raw = sample
    path = scratch / f"{kind}.toml"
    path.write_bytes(raw)
    if kind == "catalogue":
        catalogue = _loaded_or_clean_error(load_catalogue, path)
        event(f"{kind}: {'loaded' if catalogue is not None else 'SceneError'}")
        if catalogue is not None:
            _check_catalogue(catalogue)
    else:
        scene = _loaded_or_clean_error(lambda p: load_scene(p, catalogue=kitchen), path)
        event(f"{kind}: {'loaded' if scene is not None else 'SceneError'}")
        if scene is not None:
            _check_scene(scene, scratch, kitchen, domain)


def test_the_bases_load(scratch: Path, kitchen: Catalogue, domain: Domain) -> None:
    """The property's starting points are valid and pass its checks unmutated."""
    for kind, make in BASES.items():
        path = scratch / f"base-{kind}.toml"
        path.write_text(tomli_w.dumps(make()), encoding="utf-8")
        if kind == "catalogue":
            _check_catalogue(load_catalogue(path))
        else:
            _check_scene(load_scene(path), scratch, kitchen, domain)
