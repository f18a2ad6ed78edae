"""Type-level affordance facts and the hand-written ground truth.

A fact is a tuple whose first entry is the predicate of the paper's Table I:

* ``("isSupportive", type, part)``
* ``("isSupportable", type, part)``
* ``("isP2PSupportive", part2, type2, part1, type1)`` – part2 of type2 supports type1 on part1
* ``("canGraspFrom", type, member, palm, finger1, finger2)``
* ``("canLift", type, member)``
* ``("canSlide", type1, type2, part1, part2)`` – type1 slides on its part1 across part2 of type2

and, in the extended domain ``utamp2x`` only (`utamp_gym.affordances.edge`, `EXTENDED`):

* ``("canEdgePinch", type, member, palm, finger1, finger2)`` – slid to the table's edge and
  pinched there, it lifts
* ``("canSlideEdge", type1, type2, part1, part2)`` – type1 is dragged to the edge across type2
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import tomli  # see utamp_gym.scene.fields

from utamp_gym.errors import SceneError
from utamp_gym.resources import asset_path

Fact = tuple[str, ...]
PREDICATES = (
    "isSupportive",
    "isSupportable",
    "isP2PSupportive",
    "canGraspFrom",
    "canLift",
    "canSlide",
)
EXTENDED = ("canEdgePinch", "canSlideEdge")  # the extended domain's


def fact_types(fact: Fact) -> tuple[str, ...]:
    """The object types a fact mentions."""
    pred = fact[0]
    if pred == "isP2PSupportive":
        return (fact[2], fact[4])
    if pred in ("canSlide", "canSlideEdge"):
        return (fact[1], fact[2])
    return (fact[1],)


def restrict(facts: Iterable[Fact], types: Iterable[str]) -> frozenset[Fact]:
    """Facts that mention only the given types."""
    keep = set(types)
    return frozenset(f for f in facts if set(fact_types(f)) <= keep)


class Scores(NamedTuple):
    """Precision, recall and F1 of detected facts against a reference set."""

    precision: float
    recall: float
    f1: float
    true_positives: int
    false_positives: int
    false_negatives: int


def score(detected: Iterable[Fact], reference: Iterable[Fact]) -> Scores:
    det, ref = set(detected), set(reference)
    tp, fp, fn = len(det & ref), len(det - ref), len(ref - det)
    precision = tp / (tp + fp) if tp + fp else 1.0
    recall = tp / (tp + fn) if tp + fn else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    return Scores(precision, recall, f1, tp, fp, fn)


@lru_cache(maxsize=1)
def packaged_ground_truth() -> frozenset[Fact]:
    """The packaged ground truth, read once per process (the suites and every planner call
    need it; a frozenset, so sharing it is safe)."""
    return load_ground_truth()


def load_ground_truth(path: str | Path | None = None) -> frozenset[Fact]:
    """Read the hand-written ground truth (default: the packaged kitchen objects)."""
    file = Path(path) if path is not None else asset_path("affordances", "ground_truth.toml")
    try:
        data = tomli.loads(file.read_text())
    except tomli.TOMLDecodeError as exc:
        raise SceneError(f"invalid TOML: {exc}", file=str(file)) from exc
    facts: set[Fact] = set()
    for tname, d in data.items():
        for part in d.get("supportive", []):
            facts.add(("isSupportive", tname, part))
        for part in d.get("supportable", []):
            facts.add(("isSupportable", tname, part))
        for i, entry in enumerate(d.get("supports", [])):
            if len(entry) != 3:
                raise SceneError(
                    "expected [my part, other type, other part]",
                    file=str(file),
                    field=f"{tname}.supports[{i}]",
                )
            p2, t1, p1 = entry
            facts.add(("isP2PSupportive", p2, tname, p1, t1))
        for i, entry in enumerate(d.get("grasps", [])):
            if len(entry) != 4:
                raise SceneError(
                    "expected [member, palm, finger1, finger2]",
                    file=str(file),
                    field=f"{tname}.grasps[{i}]",
                )
            facts.add(("canGraspFrom", tname, *entry))
        for member in d.get("lift", []):
            facts.add(("canLift", tname, member))
        for i, entry in enumerate(d.get("slide", [])):
            if len(entry) != 3:
                raise SceneError(
                    "expected [support type, my part, support part]",
                    file=str(file),
                    field=f"{tname}.slide[{i}]",
                )
            t2, p1, p2 = entry
            facts.add(("canSlide", tname, t2, p1, p2))
    return frozenset(facts)
