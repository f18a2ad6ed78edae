"""What the language and the templates know about a scene's objects and table regions: a
noun, a material adjective, a size relative to objects of the same noun, a category (for
sorting), the region of the table each stack stands in.

Everything here is a function of the scene (its types and initial stacks). Colour is not:
the simulator draws each instance's colour per episode (`sim.appearance`), so instructions
never mention it.
"""

from __future__ import annotations

import re
from typing import NamedTuple

from utamp_gym.scene.model import Scene

#: noun of a kitchenware family (`utamp_gym.kitchenware.FAMILIES`) or a catalogue type
NOUNS = {
    "mug": "mug", "tumbler": "tumbler", "bowl": "bowl", "plate": "plate",
    "food-box": "food box", "container": "container", "bottle": "bottle", "jar": "jar",
    "frying-pan": "frying pan", "saucepan": "saucepan", "stock-pot": "stock pot",
    "paddle-board": "paddle board", "chopping-board": "chopping board", "tray": "tray",
    "sheet-pan": "sheet pan", "utensil": "utensil",
    # the catalogue's types (assets/objects/kitchen.toml, extra.toml)
    "salt-shaker": "salt shaker", "glass-mug": "mug", "cutting-board": "cutting board",
    "wooden-tray": "tray", "soup-bowl": "bowl", "deep-plate": "plate", "tea-box": "tea box",
    "oil-bottle": "bottle", "wooden-spatula": "spatula",
}  # fmt: skip
#: the category a noun belongs to (`sort` groups by it); the words name it in instructions
CATEGORIES = {
    "tableware": ("mug", "tumbler", "bowl", "plate"),
    "cookware": ("frying pan", "saucepan", "stock pot", "sheet pan"),
    "pantry items": ("food box", "container", "bottle", "jar", "salt shaker", "tea box"),
    "boards": ("paddle board", "chopping board", "cutting board", "tray"),
    "utensils": ("utensil", "spatula"),
}
MATERIAL_WORDS = {
    "wood": "wooden", "glass": "glass", "ceramic": "ceramic", "steel": "steel",
    "cast-iron": "cast-iron", "aluminium": "aluminium", "plastic": "plastic",
    "cardboard": "cardboard",
}  # fmt: skip
#: relative size (bounding-box volume) below which two objects count as the same size
SIZE_MARGIN = 0.15
_GENERATED = re.compile(r"(?P<family>[a-z-]+)-v\d+-\d+")


def family_of(type_name: str) -> str:
    """The kitchenware family of a generated type (``mug-v1-42`` -> ``mug``), else the type."""
    m = _GENERATED.fullmatch(type_name)
    return m.group("family") if m else type_name


def noun(scene: Scene, obj: str) -> str:
    fam = family_of(scene.object(obj).type)
    return NOUNS.get(fam, fam.replace("-", " "))


def category(scene: Scene, obj: str) -> str | None:
    n = noun(scene, obj)
    return next((c for c, nouns in CATEGORIES.items() if n in nouns), None)


def material_word(scene: Scene, obj: str) -> str:
    m = scene.type_of(obj).material
    return MATERIAL_WORDS.get(m, m)


def volume(scene: Scene, obj: str) -> float:
    lo, hi = scene.type_of(obj).bbox
    return float((hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]))


def size_word(scene: Scene, obj: str) -> str | None:
    """``small`` / ``large`` for the clearly (`SIZE_MARGIN`) smallest / largest object of its
    noun in the scene, else None."""
    n, v = noun(scene, obj), volume(scene, obj)
    others = [volume(scene, o) for o in scene.object_names if o != obj and noun(scene, o) == n]
    if not others:
        return None
    if all(v * (1 + SIZE_MARGIN) < w for w in others):
        return "small"
    if all(v > w * (1 + SIZE_MARGIN) for w in others):
        return "large"
    return None


def region_words(scene: Scene) -> dict[str, str]:
    """Slot -> the words naming its region of the table (``far-left corner``, ``middle``),
    from its position (+x away from the robot, +y to its left); a slot whose words another
    shares is named by its own name."""
    words = {}
    for s in scene.slots:
        x, y = s.position
        depth = "near" if x < 0.4 else "far"
        side = "left" if y > 0.1 else "right" if y < -0.1 else ""
        words[s.name] = f"{depth}-{side} corner" if side else "middle"
    counts: dict[str, int] = {}
    for w in words.values():
        counts[w] = counts.get(w, 0) + 1
    return {s: (w if counts[w] == 1 else s) for s, w in words.items()}


class Features(NamedTuple):
    """The words a referring expression may use for one object."""

    noun: str
    material: str
    size: str | None
    inverted: bool
    region: str  # the region of the table its initial stack stands in


def features(scene: Scene, obj: str) -> Features:
    return Features(
        noun(scene, obj),
        material_word(scene, obj),
        size_word(scene, obj),
        scene.object(obj).orientation == "inverted",
        region_words(scene)[scene.slot_of(obj)],
    )


__all__ = [
    "CATEGORIES",
    "MATERIAL_WORDS",
    "NOUNS",
    "SIZE_MARGIN",
    "Features",
    "category",
    "family_of",
    "features",
    "material_word",
    "noun",
    "region_words",
    "size_word",
    "volume",
]
