"""A noisy attribute detector: the offline stand-in for the paper's VLM.

Each reported attribute (a part's shape, its food-surface flag, the object's mass
and robustness, each member's width) is corrupted independently with probability
`p`; the corrupted attributes then go through the rule parser. Randomness comes only
from the Generator passed in.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from utamp_gym.affordances.facts import Fact, Scores, restrict, score
from utamp_gym.affordances.rules import derive_affordances
from utamp_gym.scene.catalogue import ROBUSTNESS, SHAPES, Member, ObjectType
from utamp_gym.scene.geometry import Box


def corrupt_type(t: ObjectType, p: float, rng: np.random.Generator) -> ObjectType:
    """A copy of `t` whose attributes are each misreported with probability p."""
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"noise rate must be in [0, 1], got {p}")
    parts = {}
    for name, attrs in t.parts.items():
        shape, food = attrs.shape, attrs.food_surface
        if rng.random() < p:
            shape = str(rng.choice([s for s in SHAPES if s != shape]))
        if rng.random() < p:
            food = not food
        parts[name] = attrs._replace(shape=shape, food_surface=food)
    mass, robustness = t.mass, t.robustness
    if rng.random() < p:
        mass = float(t.mass * np.exp(rng.normal(0.0, 1.0)))
    if rng.random() < p:
        robustness = str(rng.choice([r for r in ROBUSTNESS if r != robustness]))
    members = {}
    for name, m in t.members.items():
        box = m.box
        if rng.random() < p:
            scale = float(np.exp(rng.normal(0.0, 0.7)))
            c, half = box.center, box.size / 2 * scale
            box = Box(tuple((c - half).tolist()), tuple((c + half).tolist()))
        members[name] = Member(m.name, m.kind, box, m.geom)
    return t._replace(parts=parts, mass=mass, robustness=robustness, members=members)


@dataclass(frozen=True)
class Detection:
    """Affordance facts from a noisy detection, with their scores against a reference."""

    facts: frozenset[Fact]
    scores: Scores


def detect_affordances(
    types: Iterable[ObjectType],
    p: float,
    rng: np.random.Generator,
    reference: Iterable[Fact],
) -> Detection:
    """Corrupt the attributes of `types`, derive facts, and score them against `reference`."""
    types = list(types)
    noisy = [corrupt_type(t, p, rng) for t in types]
    facts = derive_affordances(noisy)
    ref = restrict(reference, [t.name for t in types])
    return Detection(facts, score(facts, ref))
