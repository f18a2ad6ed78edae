"""The perceiver protocol: what a replaceable perceiver is given and what it returns.

A perceiver turns one look at the table into the attributes the affordance rules read. Its
request (`PerceptionRequest`) is plain data: the rendered views (`ViewBundle`: per camera
RGB, metric depth, object-level instance masks, intrinsics and the camera's world pose, plus
the robot's state), and the scene's object names with the instance id each has in the masks
and the orientation it stands in (its catalogue type is to be written in that frame). It
never gets the scene's declared types.

Its result is one `PerceivedAttributes` per object name: an `ObjectType` (the fields the
rules read: parts, members, material, mass, robustness) and, per attribute named as in
`utamp_gym.methods.attributes.ATTRIBUTES`, the probability that the value given is right
(`confidence`; an attribute not listed is certain) and the other plausible values, most
likely first (`alternatives`: a material name, a mass in kg, a robustness, ...). An object
it cannot perceive is left out (the evaluation then charges the run to perception).

`utamp eval --methods utamp2-perceived:PACKAGE.MODULE:CLASS` builds ``CLASS()`` and calls
its `perceive` (`utamp_gym.methods.perceivers.load_perceiver`); the built-in perceiver and
the VLM client are implementations (`utamp_gym.methods.perceivers`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from utamp_gym.contract.views import ViewBundle
from utamp_gym.scene.catalogue import ObjectType


@dataclass(frozen=True, eq=False)
class PerceptionRequest:
    """One look to perceive: the views, and the scene's objects as the masks name them."""

    bundle: ViewBundle
    instances: Mapping[int, str]  # instance id in the masks -> object name
    orientations: Mapping[str, str]  # object name -> "upright" | "inverted" | ...
    rgb_png: bytes | None = field(default=None, repr=False)  # an overview image, if any

    @property
    def object_names(self) -> tuple[str, ...]:
        return tuple(self.instances.values())


@dataclass(frozen=True)
class PerceivedAttributes:
    """What a perceiver reports for one object (module docstring)."""

    type: ObjectType
    confidence: Mapping[str, float] = field(default_factory=dict)
    alternatives: Mapping[str, tuple[Any, ...]] = field(default_factory=dict)

    def confidence_of(self, attribute: str) -> float:
        """The probability the reported value of `attribute` is right (1.0 if not given)."""
        return float(self.confidence.get(attribute, 1.0))


@runtime_checkable
class Perceiver(Protocol):
    """Anything with this method is a perceiver (module docstring)."""

    def perceive(self, request: PerceptionRequest) -> Mapping[str, PerceivedAttributes]:
        """Object name -> its perceived attributes (objects not perceived are left out)."""
        ...


__all__ = ["PerceivedAttributes", "Perceiver", "PerceptionRequest"]
