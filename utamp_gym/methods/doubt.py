"""Planning under doubt: an attribute the perceiver is unsure of takes the value that promises less.

Where a perceiver reports an attribute's confidence below `DOUBT_THRESHOLD` and offers
alternatives (`utamp_gym.contract.perceiver.PerceivedAttributes`), the planning scene gets,
of the reported value and its alternatives, the one under which the object takes part in the
fewest affordance facts (the rules decide what "promises less" means: a support that may be
fragile carries less than a sturdy one, a heavier mass class is lifted by fewer grasps and
rests on fewer supports, a material that rules out a grasp gives fewer). Ties keep the
reported value. A scene the cautious values make unsolvable is planned with the likely
values instead, and that is marked (`DoubtfulPlan.fell_back`); one the likely values leave
unsolvable too is planned hoping (`DoubtfulPlan.hoped`): every attribute at the value that
promises most, and every fact some reading allows (`hoped_facts`) -- the plan the closed
loop would test by acting, played open loop.

An alternative is applied by `with_value`: ``material``, ``mass`` (kg) and ``robustness``
replace the type's field; an alternative that is a whole `ObjectType` replaces the type's
geometry, its members and parts (how a perceiver offers another reading of the geometry:
members, shapes, surfaces, sizes), and keeps the material, mass and robustness.

Some readings are not ordered by promise (`READINGS`: ``member_size``, the body read a
little narrower or wider: a narrower one fits into the hand and onto more supports, a wider
one carries more; ``surface``, a top or bottom surface read so), and some alternatives
promise other things (a mass light enough to lift, a heavier one the rules let the arm
slide). Hoping, they are not chosen between: every fact that holds under some alternative
of the objects it concerns is hoped for (`hoped_facts`), for the robot's acts to test.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.sources import plan_affordances
from utamp_gym.contract.perceiver import PerceivedAttributes
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.model import Scene

#: an attribute reported with a lower confidence than this is planned cautiously
DOUBT_THRESHOLD = 0.8
SCALAR = ("material", "mass", "robustness")
#: attributes whose alternatives are readings no one of which promises most (docstring)
READINGS = ("member_size", "surface")


@dataclass(frozen=True)
class Doubt:
    """One attribute planned with a value other than the likely one."""

    object: str
    attribute: str
    likely: Any
    cautious: Any
    confidence: float

    def __str__(self) -> str:
        return (
            f"{self.object}.{self.attribute}: planned as {_show(self.cautious)} "
            f"(read {_show(self.likely)} at p={self.confidence:.2f})"
        )


def _show(value: Any) -> str:
    return value.name if isinstance(value, ObjectType) else repr(value)


def with_value(t: ObjectType, attribute: str, value: Any) -> ObjectType | None:
    """`t` with `attribute` set to `value` (module docstring); None if it cannot be applied."""
    if isinstance(value, ObjectType):
        return t._replace(members=value.members, parts=value.parts)
    if attribute == "mass":
        try:
            return t._replace(mass=float(value))
        except (TypeError, ValueError):
            return None
    if attribute in SCALAR:
        return t._replace(**{attribute: str(value)})
    return None


def value_of(t: ObjectType, attribute: str) -> Any:
    return getattr(t, attribute) if attribute in SCALAR else t


def _involving(facts: frozenset[Fact], type_name: str) -> int:
    return sum(1 for f in facts if type_name in f[1:])


def cautious_types(
    planning: Scene,
    types: Mapping[str, ObjectType],
    reports: Mapping[str, PerceivedAttributes],
    threshold: float = DOUBT_THRESHOLD,
    affordances: Callable[[Scene], frozenset[Fact]] = plan_affordances,
    *,
    hopeful: bool = False,
) -> tuple[dict[str, ObjectType], tuple[Doubt, ...]]:
    """Object -> type with every doubtful attribute at its cautious value, and the doubts
    acted on. `types`: object -> its perceived type (named ``<object>-seen``) as in
    `planning`, whose catalogue is updated as values are chosen (one attribute at a time,
    in the order reported, each judged with the earlier choices in place). `hopeful`: the
    value that promises *most* instead, for every attribute with alternatives (what the
    closed loop tries, and then tests by acting, when nothing else reaches the goal)."""
    out = dict(types)
    doubts: list[Doubt] = []
    for obj, report in reports.items():
        if obj not in out:
            continue
        for attribute in report.alternatives if hopeful else report.confidence:
            p = report.confidence_of(attribute)
            alts = tuple(report.alternatives.get(attribute, ()))
            if (p >= threshold and not hopeful) or not alts or (hopeful and attribute in READINGS):
                continue
            current = out[obj]
            candidates = [current]
            for v in alts:
                t = with_value(current, attribute, v)
                if t is not None and t != current:
                    candidates.append(t)
            if len(candidates) == 1:
                continue
            counts = []
            for t in candidates:
                scene = _with_type(planning, t)
                counts.append(_involving(affordances(scene), t.name))
            sign = -1 if hopeful else 1
            best = min(range(len(candidates)), key=lambda i: (sign * counts[i], i))
            if best:
                chosen = candidates[best]
                doubts.append(
                    Doubt(obj, attribute, value_of(current, attribute),
                          value_of(chosen, attribute), float(p))
                )  # fmt: skip
                out[obj] = chosen
                planning = _with_type(planning, chosen)
    return out, tuple(doubts)


def hoped_facts(
    planning: Scene,
    types: Mapping[str, ObjectType],
    reports: Mapping[str, PerceivedAttributes],
    affordances: Callable[[Scene], frozenset[Fact]] = plan_affordances,
    *,
    singles: bool = True,
    pairs: bool = True,
) -> frozenset[Fact]:
    """The facts of `planning` that hold under some alternative the perceiver offers for
    the objects they concern (`types`: object -> its type as in `planning`): under each
    alternative of each attribute, one object at a time (a mass light enough to lift and
    the heavier one that may be slid), and (`pairs`) under the `READINGS` alternatives two
    objects at a time -- a fact concerns at most two objects, so this is every fact some
    joint reading of the sizes allows (the facts of the reported values themselves are not
    included). Without `pairs`: the facts one misreading allows; without `singles`: those
    only the two-object readings add to them."""
    alone: list[ObjectType] = []
    readings: dict[str, list[ObjectType]] = {}
    for obj, report in reports.items():
        if obj not in types:
            continue
        for attribute, values in report.alternatives.items():
            for value in values:
                t = with_value(types[obj], attribute, value)
                if t is None or t == types[obj]:
                    continue
                alone.append(t)
                if attribute in READINGS:
                    readings.setdefault(obj, []).append(t)
    out: set[Fact] = set()
    for t in alone if singles else ():
        out |= affordances(_with_type(planning, t))
    for a, b in itertools.combinations(readings if pairs else (), 2):
        for ta, tb in itertools.product(readings[a], readings[b]):
            out |= affordances(_with_type(_with_type(planning, ta), tb))
    return frozenset(out)


def _with_type(planning: Scene, t: ObjectType) -> Scene:
    """`planning` with the catalogue type of `t`'s name replaced."""
    return planning._replace(
        catalogue=planning.catalogue.merged({t.name: t}),
        custom_types={**planning.custom_types, t.name: t},
    )


@dataclass(frozen=True)
class DoubtfulPlan:
    """How doubt was handled: the doubts planned cautiously, or (`fell_back`) the doubts
    whose cautious values made the goal unsolvable, so the likely values were planned, or
    (`hoped`) the likely values left it unsolvable too, so the values that promise most
    (`doubts`: those taken) and the facts of every alternative (`hoped_facts`) were planned."""

    doubts: tuple[Doubt, ...] = ()
    fell_back: bool = False
    hoped: bool = False

    def note(self) -> str:
        """A one-line account for a result row ("" if no attribute was in doubt)."""
        if self.hoped:
            what = "; ".join(map(str, self.doubts)) or "sizes"
            return f"likely values unsolvable, planned hoping ({what})"
        if not self.doubts:
            return ""
        what = "; ".join(map(str, self.doubts))
        if self.fell_back:
            return f"cautious values unsolvable, planned the likely ones ({what})"
        return f"planned under doubt ({what})"


__all__ = [
    "DOUBT_THRESHOLD",
    "READINGS",
    "Doubt",
    "DoubtfulPlan",
    "cautious_types",
    "hoped_facts",
    "value_of",
    "with_value",
]
