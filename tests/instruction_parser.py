"""A parser of instructions for the tests (not in the product): text -> every (template,
params) reading whose object mentions each resolve to exactly one object of the scene.

It reads the phrasings as patterns (``{name}`` slots between literal text) and tries every
way of cutting the text at the literal parts (backtracking), so a reading is found however
the slots' text looks; the product's instruction is unambiguous when exactly one reading
survives. Referring expressions are resolved here from the objects' attributes: ``the
[small|large] [MATERIAL] [upside-down] NOUN [in the REGION]``.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

from utamp_gym.scene.model import Scene
from utamp_gym.tasks.attributes import CATEGORIES, MATERIAL_WORDS, features, region_words
from utamp_gym.tasks.language import JOIN
from utamp_gym.tasks.templates import SORT_TWO, TEMPLATES

_SLOT = re.compile(r"\{(\w+)\}")


def resolve(scene: Scene, text: str) -> str | None:
    """The one object `text` names, else None."""
    if not text.startswith("the "):
        return None
    words = text[4:]
    region = None
    if " in the " in words:
        words, region = words.split(" in the ", 1)
    tokens = words.split()
    size = tokens.pop(0) if tokens and tokens[0] in ("small", "large") else None
    material = tokens.pop(0) if tokens and tokens[0] in MATERIAL_WORDS.values() else None
    inverted = bool(tokens and tokens[0] == "upside-down")
    if inverted:
        tokens.pop(0)
    noun = " ".join(tokens)
    hits = []
    for o in scene.object_names:
        f = features(scene, o)
        if f.noun != noun or (material is not None and f.material != material):
            continue
        if (size is not None and f.size != size) or (inverted and not f.inverted):
            continue
        if region is not None and f.region != region:
            continue
        hits.append(o)
    return hits[0] if len(hits) == 1 else None


def resolve_list(scene: Scene, text: str) -> tuple[str, ...] | None:
    items = text.split(", ")
    if " and " not in items[-1]:
        if len(items) > 1:
            return None
        one = resolve(scene, text)
        return None if one is None else (one,)
    *head, last = items
    a, _, b = last.rpartition(" and ")
    names = [resolve(scene, t) for t in (*head, a, b)]
    if any(n is None for n in names) or len(set(names)) != len(names):
        return None
    return tuple(n for n in names if n is not None)


def _value(scene: Scene, name: str, text: str, lists: tuple[str, ...]) -> Any:
    if name.startswith("category"):
        return text if text in CATEGORIES else None
    if name == "region":
        words = {f"the {w} of the table": s for s, w in region_words(scene).items()}
        return words.get(text)
    if name in lists:
        return resolve_list(scene, text)
    return resolve(scene, text)


def _match(scene: Scene, pattern: str, text: str, lists: tuple[str, ...]) -> Iterator[dict]:
    """Every assignment of the pattern's slots that reproduces `text`."""
    pieces = _SLOT.split(pattern)  # literal, slot, literal, slot, ..., literal
    if not text.startswith(pieces[0]):
        return

    def walk(i: int, pos: int, got: dict) -> Iterator[dict]:
        if i >= len(pieces):
            if pos == len(text):
                yield dict(got)
            return
        slot, literal = pieces[i], pieces[i + 1]
        ends = [len(text)] if not literal else [
            m.start() for m in re.finditer(re.escape(literal), text[pos:])
        ]  # fmt: skip
        for end in ends:
            stop = pos + end if literal else end
            value = _value(scene, slot, text[pos:stop], lists)
            if value is None:
                continue
            yield from walk(i + 2, stop + len(literal), {**got, slot: value})

    yield from walk(1, len(pieces[0]), {})


def _unstack_objects(scene: Scene, base: str) -> tuple[str, ...]:
    chain = scene.stacks[scene.slot_of(base)]
    return tuple(chain[chain.index(base) + 1 :])


def readings(scene: Scene, text: str) -> list[tuple[str, dict[str, Any]]]:
    """Every (template id, params) the text can mean in the scene."""
    per_part: list[list[tuple[str, dict]]] = []
    for part in text.split(JOIN):
        found = []
        for t in TEMPLATES.values():
            patterns = t.phrasings + (SORT_TWO if t.id == "sort" else ())
            for pattern in patterns:
                for got in _match(scene, pattern, part, t.lists):
                    if t.id == "unstack":
                        got["objects"] = _unstack_objects(scene, got["base"])
                    if (t.id, got) not in found:
                        found.append((t.id, got))
        per_part.append(found)
    if len(per_part) == 1:
        return per_part[0]
    out: list[tuple[str, dict[str, Any]]] = []

    def combine(i: int, names: list[str], params: dict) -> None:
        if i == len(per_part):
            out.append(("+".join(names), params))
            return
        for name, p in per_part[i]:
            combine(i + 1, [*names, name], {**params, **{f"{i + 1}.{k}": v for k, v in p.items()}})

    combine(0, [], {})
    return out
