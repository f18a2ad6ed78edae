"""Instructions from goals: deterministic text from the goal's template, its parameters and
the objects' attributes (`utamp_gym.tasks.attributes`).

**Referring expressions.** An object is named by the shortest description, in the order
below, that fits it and no other object of the scene (`refer`):

    the NOUN / the MATERIAL NOUN / the SIZE NOUN / the SIZE MATERIAL NOUN /
    the [SIZE] [MATERIAL] upside-down NOUN / ... in the REGION

SIZE is ``small`` or ``large`` (the clearly smallest / largest of its noun in the scene),
REGION the table region its initial stack stands in (``far-left corner``, ``middle``). An
object no description singles out has no expression (`AmbiguousReference`); the samplers
(`utamp_gym.tasks.sampling`) then draw another goal. Lists read ``the mug, the bowl and the
plate``; a region is ``the far-left corner of the table``; a category its word
(``cookware``).

**Phrasings.** Every template has several (`Template.phrasings`); which one a goal gets is
`phrasing_index`: the SHA-256 of ``"<scene name>|<goal JSON>|<seed>|<part>"`` modulo their
number, so the text is a pure function of (scene, goal, seed); seed 0 is what the suites
show. A composition joins its parts' instructions with ``", and then "``.
"""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Sequence
from typing import Any

from utamp_gym.errors import UtampError
from utamp_gym.scene.model import Scene
from utamp_gym.tasks.attributes import Features, features, region_words
from utamp_gym.tasks.goal import CUSTOM, Goal
from utamp_gym.tasks.templates import SORT_TWO, part_params, parts, template

JOIN = ", and then "


class AmbiguousReference(UtampError, ValueError):
    """No description names an object of the scene and no other."""


def _words(f: Features, use: Sequence[str]) -> str:
    words = ["the"]
    if "size" in use:
        words.append(str(f.size))
    if "material" in use:
        words.append(f.material)
    if "inverted" in use:
        words.append("upside-down")
    words.append(f.noun)
    if "region" in use:
        words += ["in", "the", f.region]
    return " ".join(words)


def _fits(f: Features, g: Features, use: Sequence[str]) -> bool:
    """Whether object features `g` fit the description of `f` that uses `use`."""
    return f.noun == g.noun and all(getattr(f, k) == getattr(g, k) for k in use)


#: the descriptions tried, shortest first (attribute sets besides the noun)
_BASE_ORDER: tuple[tuple[str, ...], ...] = (
    (), ("material",), ("size",), ("size", "material"), ("inverted",),
    ("material", "inverted"), ("size", "material", "inverted"),
)  # fmt: skip
ORDER = (*_BASE_ORDER, *((*c, "region") for c in _BASE_ORDER))


def refer(scene: Scene, obj: str) -> str:
    """The shortest unambiguous description of `obj` (module docstring)."""
    mine = features(scene, obj)
    others = [features(scene, o) for o in scene.object_names if o != obj]
    for use in ORDER:
        if ("size" in use and mine.size is None) or ("inverted" in use and not mine.inverted):
            continue
        if not any(_fits(mine, g, use) for g in others):
            return _words(mine, use)
    raise AmbiguousReference(f"{scene.name}: no description singles out '{obj}'")


def listing(names: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def region_phrase(scene: Scene, slot: str) -> str:
    return f"the {region_words(scene)[slot]} of the table"


def phrasing_index(scene: Scene, goal: Goal, seed: int, part: int, n: int) -> int:
    key = f"{scene.name}|{goal.to_json()}|{seed}|{part}".encode()
    return int.from_bytes(hashlib.sha256(key).digest()[:8], "big") % n


def _fill(scene: Scene, text: str, params: dict[str, Any]) -> str:
    values: dict[str, str] = {}
    for k, v in params.items():
        if k.startswith("category"):
            values[k] = str(v)
        elif k == "region":
            values[k] = region_phrase(scene, str(v))
        elif isinstance(v, (list, tuple)):
            values[k] = listing([refer(scene, x) for x in v])
        else:
            values[k] = refer(scene, str(v))
    return text.format(**values)


def phrasings(name: str, params: dict[str, Any]) -> tuple[str, ...]:
    """A template's phrasings for these parameters (sort with two groups has its own)."""
    if name == "sort" and "base2" in params:
        return SORT_TWO
    return template(name).phrasings


def instruction(scene: Scene, goal: Goal, seed: int = 0) -> str:
    """The instruction of `goal` in `scene` (`AmbiguousReference` if an object it names has no
    unambiguous description; ValueError for a custom goal, which has no template)."""
    if goal.template == CUSTOM:
        raise ValueError("a custom goal (literals only) has no instruction")
    texts = []
    for i, (name, p) in enumerate(
        zip(parts(goal.template), part_params(goal.template, goal.param_dict), strict=True)
    ):
        options = phrasings(name, p)
        text = options[phrasing_index(scene, goal, seed, i, len(options))]
        texts.append(_fill(scene, text, p))
    return JOIN.join(texts)


def all_instructions(scene: Scene, goal: Goal) -> list[str]:
    """Every phrasing combination of the goal (for tests and for agents that want variety)."""
    per_part = [
        [_fill(scene, t, p) for t in phrasings(name, p)]
        for name, p in zip(
            parts(goal.template), part_params(goal.template, goal.param_dict), strict=True
        )
    ]
    return [JOIN.join(c) for c in itertools.product(*per_part)]


__all__ = [
    "JOIN",
    "ORDER",
    "AmbiguousReference",
    "all_instructions",
    "instruction",
    "listing",
    "phrasing_index",
    "phrasings",
    "refer",
    "region_phrase",
]
