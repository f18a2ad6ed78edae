"""Procedural kitchenware: object types sampled from families of real kitchenware.

The layer above `utamp_gym.scene`: it emits catalogue types (`ObjectType`) and nothing below
it knows a family. An instance is a pure function of (family, version, seed)::

    from utamp_gym.kitchenware import generate
    mug = generate("mug", "v1", 42)      # an ObjectType named "mug-v1-42"

Each family (`FAMILIES`) declares its parameters with ranges from real products and their
sources (`Param`, `sources.SOURCES`), its materials, and a builder that turns the drawn
dimensions into members (boxes and cylinders), part attributes, a mass (the solid volume
times the material's density, `utamp_gym.scene.materials`, plus any contents) and the
material's robustness. Types carry no colour: the simulator gives every instance a colour and
finish from its material's palette. Bodies, grasps, placements and affordances follow from
these attributes alone (`utamp_gym.sim.bodies`, `utamp_gym.affordances.rules`).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from types import MappingProxyType
from typing import Any

from utamp_gym.errors import UnknownNameError
from utamp_gym.kitchenware.cookware import FRYING_PAN, SAUCEPAN, STOCK_POT
from utamp_gym.kitchenware.flatware import (
    CHOPPING_BOARD,
    PADDLE_BOARD,
    PLATE,
    SHEET_PAN,
    TRAY,
    UTENSIL,
)
from utamp_gym.kitchenware.params import Family, Instance, Param, draw, extremes
from utamp_gym.kitchenware.vessels import BOTTLE, BOWL, BOX, CONTAINER, JAR, MUG, TUMBLER
from utamp_gym.scene.catalogue import Member, ObjectType, PartAttrs, parse_type
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.materials import material

VERSIONS = ("v1",)
FAMILIES: Mapping[str, Family] = MappingProxyType(
    {
        f.name: f
        for f in (
            MUG, TUMBLER, BOWL, PLATE, BOX, CONTAINER, BOTTLE, JAR,
            FRYING_PAN, SAUCEPAN, STOCK_POT,
            PADDLE_BOARD, CHOPPING_BOARD, TRAY, SHEET_PAN, UTENSIL,
        )
    }
)  # fmt: skip


def family(name: str) -> Family:
    """The family called `name`; an unknown name lists the valid ones."""
    try:
        return FAMILIES[name]
    except KeyError:
        raise UnknownNameError("kitchenware family", name, FAMILIES) from None


def type_name(family_name: str, version: str, seed: int) -> str:
    return f"{family_name}-{version}-{seed}"


def type_table(fam: Family, inst: Instance) -> dict[str, Any]:
    """The type table (catalogue schema) of a drawn instance."""
    built = fam.build(inst)
    mass = round(built.solid_volume * inst.density + built.contents_kg, 3)
    return {
        **built.table,
        "mass": max(mass, 0.001),
        "material": inst.material,
        "robustness": material(inst.material).robustness,
    }


def build_type(fam: Family, inst: Instance, name: str, *, validate: bool = True) -> ObjectType:
    """The catalogue type of a drawn instance. Validated by the catalogue's own parser (so a
    generated type and its scene-file text are the same), or, with ``validate=False``, built
    directly (the scene generator tries many candidates; the scene file it writes is parsed
    and validated as any other; tests/test_kitchenware.py checks both agree)."""
    data = type_table(fam, inst)
    if validate:
        return parse_type(name, data, file=f"<kitchenware {fam.name} {inst.version} {inst.seed}>")
    members = {
        n: Member(n, m["kind"], Box(tuple(m["min"]), tuple(m["max"])), m["geom"])  # type: ignore[arg-type]
        for n, m in data["members"].items()
    }
    parts = {
        n: PartAttrs(
            p["shape"],
            tuple(p["size"]) if "size" in p else None,  # type: ignore[arg-type]
            bool(p.get("food_surface", False)),
            p.get("height"),
            tuple(p["center"]) if "center" in p else None,  # type: ignore[arg-type]
        )
        for n, p in data["parts"].items()
    }
    return ObjectType(
        name, float(data["mass"]), data["material"], data["robustness"], members, parts,
        description=data["description"],
    )  # fmt: skip


@lru_cache(maxsize=8192)
def generate(family_name: str, version: str, seed: int, *, validate: bool = True) -> ObjectType:
    """The instance `seed` of a family in a generator version (a pure function of the three;
    `validate`: see `build_type`)."""
    if version not in VERSIONS:
        raise UnknownNameError("kitchenware version", version, VERSIONS)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise ValueError(f"seed must be an integer in [0, 2**63), got {seed!r}")
    fam = family(family_name)
    name = type_name(family_name, version, seed)
    return build_type(fam, draw(fam, version, seed), name, validate=validate)


def extreme_type(family_name: str, mat: str, high: bool) -> ObjectType:
    """A family's type with every parameter at its low or high end (for body tests)."""
    fam = family(family_name)
    name = f"{family_name}-{mat}-{'high' if high else 'low'}"
    return build_type(fam, extremes(fam, mat, high), name)


__all__ = [
    "FAMILIES",
    "VERSIONS",
    "Family",
    "Instance",
    "Param",
    "extreme_type",
    "family",
    "generate",
    "type_name",
]
