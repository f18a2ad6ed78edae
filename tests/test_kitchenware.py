"""Procedural kitchenware: families, their parameter tables, determinism, the layer boundary.

Bodies of every family at its parameter extremes are ray-cast in tests/test_sim_bodies.py.
"""

from __future__ import annotations

import ast
import pickle
from pathlib import Path

import pytest

import utamp_gym
from utamp_gym.errors import UnknownNameError
from utamp_gym.kitchenware import FAMILIES, VERSIONS, extreme_type, family, generate
from utamp_gym.kitchenware.params import UNITS, draw
from utamp_gym.kitchenware.sources import SOURCES
from utamp_gym.scene.catalogue import parse_type, type_to_dict
from utamp_gym.scene.materials import MATERIALS, material

PACKAGE = Path(utamp_gym.__file__).parent


def test_at_least_twelve_families_with_documented_parameters() -> None:
    assert len(FAMILIES) >= 12
    for fam in FAMILIES.values():
        assert fam.summary and fam.doc and fam.materials and fam.params
        assert set(fam.sources) <= set(SOURCES), fam.name
        for mat, weight in fam.materials:
            assert mat in MATERIALS and weight > 0, (fam.name, mat)
        for p in fam.params:
            assert p.lo <= p.hi and p.unit in UNITS and p.doc, (fam.name, p.name)
            assert p.source in SOURCES, (fam.name, p.name, p.source)
            if p.real is not None:  # the sampled range lies within what real products span
                assert p.real[0] <= p.lo and p.hi <= p.real[1], (fam.name, p.name)
            assert not p.materials or set(p.materials) <= {m for m, _ in fam.materials}


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_instances_are_pure_functions_of_family_version_seed(name: str) -> None:
    a = generate(name, "v1", 12345)
    generate.cache_clear()
    b = generate(name, "v1", 12345)
    assert a is not b and a == b and type_to_dict(a) == type_to_dict(b)
    assert pickle.loads(pickle.dumps(a)) == a
    c = generate(name, "v1", 12346)
    assert c != a and c.name == f"{name}-v1-12346"


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_generated_types_are_valid_catalogue_types(name: str) -> None:
    fam = family(name)
    for seed in range(40):
        t = generate(name, "v1", seed)
        # the fast path the scene generator uses builds the same type
        assert generate(name, "v1", seed, validate=False) == t
        assert parse_type(t.name, type_to_dict(t), "<round trip>") == t
        assert "rgba" not in t.extra  # the simulator colours instances by material
        assert t.material in {m for m, _ in fam.materials}
        assert t.robustness == material(t.material).robustness
        inst = draw(fam, "v1", seed)
        for p in fam.params:  # every drawn value lies in its declared range (rounded)
            if p.applies(inst.material):
                scale, digits = UNITS[p.unit]
                value = inst[p.name] / scale
                assert p.lo - 10**-digits / scale <= value <= p.hi + 10**-digits / scale
        lengths = [v for m in type_to_dict(t)["members"].values() for v in (*m["min"], *m["max"])]
        assert all(round(v, 4) == v for v in lengths)  # 0.1 mm grid: stable text
        assert round(t.mass, 3) == t.mass and t.mass > 0


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_an_upside_down_instance_carries_over_its_own_bottom(name: str) -> None:
    """What stands on an upside-down instance is centred on the surface its bottom offers:
    that centre must lie over a member that reaches the bottom, not over a handle's share of
    the bounding box (a jar set on an upside-down saucepan's bounding-box centre stood
    beyond the pan's floor, over a handle 7 cm above the table, and fell)."""
    fam = family(name)
    types = [generate(name, "v1", seed) for seed in range(20)]
    types += [extreme_type(name, mat, high) for mat, _ in fam.materials for high in (False, True)]
    for t in types:
        if t.parts["under"].shape != "flat":
            continue
        cx, cy = t.surface_center("under")
        bottom = t.bbox.min[2]
        feet = [m.box for m in t.members.values() if m.box.min[2] <= bottom + 1e-9]
        assert any(b.min[0] <= cx <= b.max[0] and b.min[1] <= cy <= b.max[1] for b in feet), t.name


def test_mass_is_density_times_volume() -> None:
    """Same geometry, denser material: heavier in proportion (the plate has no contents)."""
    fam = family("plate")
    inst = draw(fam, "v1", 3)
    light = extreme_type("plate", inst.material, False)
    from utamp_gym.kitchenware import build_type

    heavy = build_type(fam, inst._replace(density=2 * inst.density), "plate-heavy")
    same = build_type(fam, inst, "plate-same")
    assert heavy.mass == pytest.approx(2 * same.mass, abs=0.002)
    assert light.mass < same.mass or light.mass == pytest.approx(same.mass, rel=0.5)


def test_unknown_names_list_the_valid_ones() -> None:
    with pytest.raises(UnknownNameError, match="bottle, bowl, chopping-board"):
        generate("teapot", "v1", 0)
    with pytest.raises(UnknownNameError, match=", ".join(VERSIONS)):
        generate("mug", "v9", 0)
    with pytest.raises(ValueError, match="seed"):
        generate("mug", "v1", -1)


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_no_layer_below_the_generator_knows_it() -> None:
    """Only the suites (and the kitchenware package itself) import the generator, and no
    module below it names a family: bodies, grasps and affordances come from attributes."""
    above = {"kitchenware", "suites"}
    families = set(FAMILIES)
    for path in PACKAGE.rglob("*.py"):
        layer = path.relative_to(PACKAGE).parts[0]
        if layer in above:
            continue
        imports = _imports(path)
        assert not any(m.startswith("utamp_gym.kitchenware") for m in imports), path
        if layer in ("scene", "affordances", "sim", "symbolic", "planning", "robot"):
            strings = {
                n.value
                for n in ast.walk(ast.parse(path.read_text()))
                if isinstance(n, ast.Constant) and isinstance(n.value, str)
            }
            assert not strings & families, (path, strings & families)
