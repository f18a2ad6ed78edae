"""Why a rule refuses: the structured reason the affordance rules decide by.

Each rule of `utamp_gym.affordances.rules` and `utamp_gym.affordances.hand` has a
``*_refusal`` twin that returns None when the rule grants the affordance, else a `Refusal`:
the rule's name and the numbers it compared. The boolean rule is ``refusal is None``, so an
explanation and the decision it explains cannot disagree. The text (`Refusal.detail`) is
formatted only when asked for, and a decision asks with ``why=False``: the refusal is then
the shared `REFUSED`, built once (the scene generator asks the rules many thousand times).

Lengths in `values` are metres, masses kilograms, moments newton metres; the text shows
centimetres.
"""

from __future__ import annotations

from typing import Any, NamedTuple

#: rule -> how its values read: ``{x:cm}`` a length in cm, ``{x:cm2}`` a pair of them, a
#: nested `Refusal` as its sentence; one sentence, no final stop
TEMPLATES: dict[str, str] = {
    "fixed": "{type} is fixed furniture: it is never moved",
    "same-type": "an object never stands on another of its own type ({type})",
    "load-capacity": (
        "mass {mass:.2f} kg > {capacity:.1f} kg, the load a {robustness} {supporter} carries"
    ),
    "surface-shape": "{type}'s {part} is {shape}: only a flat or open part rests on something",
    "food-surface": "{type}'s {part} is a food surface: it is never put face-down",
    "fixed-top-only": "fixed furniture supports on a flat top only ({type}'s {part} is {shape})",
    "support-shape": "{type}'s {part} is {shape}: only a flat or concave part carries things",
    "never-up": "{type}'s {part} never faces up, as {why}",
    "tips-over": (
        "{type}'s centre of mass lies {offset:cm2} cm off the middle of its {part} surface, "
        "beyond {half:cm2} cm (half the surface) less {margin:cm} cm: it tips over"
    ),
    "footprint": (
        "{type}'s footprint {footprint:cm2} cm{margin_note} exceeds {supporter}'s {part} "
        "surface {surface:cm2} cm"
    ),
    "footprint-disc": (
        "{type}'s footprint {size:cm} cm across{margin_note} exceeds {supporter}'s round "
        "{part} surface of {disc:cm} cm"
    ),
    "span": (
        "{type}'s standing surface {standing:cm2} cm does not span {supporter}'s {part} "
        "opening {opening:cm2} cm with {margin:cm} cm to spare a side"
    ),
    "palm-never-up": "the palm would rest on its {palm}, which never faces up, as {why}",
    "covered": "{other} stands over {member}'s {palm} face: the hand cannot come down onto it",
    "too-thin": "{member} is {width:cm} cm across ({fingers}): thinner than {limit:cm} cm",
    "grip-width": (
        "{member} is {width:cm} cm across ({fingers}) > {limit:cm} cm, what the "
        "{opening:cm} cm opening {how}"
    ),
    "finger-blocked": "{other} lies within {gap:cm} cm of {member}'s {side} side",
    "pinch": (
        "{member} is a {width:cm} cm wall ({fingers}): thinner than the {limit:cm} cm "
        "the squeezed fingers feel"
    ),
    "hand-room": "closing on {member} ({fingers}), the hand would land on {other}",
    "wrist-room": "closing on {member} ({fingers}), the wrist above the hand would land on {other}",
    "finger-room": (
        "closing on {member} ({fingers}), the {side} finger would stop {shortfall:cm} cm "
        "above its target, on its {other} ({tolerance:cm} cm allowed)"
    ),
    "payload": (
        "mass {mass:.2f} kg > {limit:.2f} kg, what a {kind} grasp lifts "
        "(the Panda's payload: {payload:.1f} kg)"
    ),
    "torque": (
        "held by {member}, its weight turns it between the pads: {moment:.2f} N m "
        "({mass:.2f} kg at {lever:cm} cm) > {limit:.1f} N m"
    ),
    "rim": "{member} is no rim pinched from above: {what}",
    "rim-across": (
        "{member} is {width:cm} cm across ({fingers}), wider than its {lateral:cm} cm along "
        "the rim: the fingers would not straddle the wall"
    ),
    "rim-width": "{member} is {width:cm} cm across ({fingers}), outside {limits:cm2} cm",
    "rim-finger-room": (
        "pinching {member} ({fingers}), a finger would stop {shortfall:cm} cm above its "
        "target ({tolerance:cm} cm allowed, pad on the rim {pad_overlap:cm} cm)"
    ),
    "rim-flare": (
        "{member}'s wall slopes out {flare:cm} cm from its foot to its rim (> {limit:cm} cm): "
        "the pads would meet it along a line and it would pivot between them"
    ),
    "rim-payload": "mass {mass:.2f} kg > {limit:.2f} kg, what a rim pinch lifts",
    "edge-slab": "no slab to slide to the table's edge and pinch there: {what}",
    "edge-thickness": "{thickness:cm} cm thick, outside {limits:cm2} cm an edge pinch closes on",
    "edge-end": ("its back end ({member}) is no solid slab the pads close on over {depth:cm} cm"),
    "edge-com": (
        "overhanging the table's edge, its centre of mass would lie {inside:cm} cm inside "
        "it (< {margin:cm} cm): it would tip off"
    ),
    "edge-drag": "mass {mass:.2f} kg > {limit:.1f} kg, what the pressing fingertips drag",
    "edge-wide": (
        "{half:cm} cm from its middle to its side: dragged {line:cm} cm from the robot's "
        "axis it would come within {clearance:cm} cm of the base"
    ),
    "ground-truth": "{fact} is not in the hand-written ground truth (the rules grant it)",
    "off-tower": "{supporter} cannot join the tower itself",
    "one-tower": "every object can join the tower on its own, but not all together: {rest}",
    "goal-order": (
        "each object the goal moves can be picked up and put down where it allows, but no "
        "order of moves reaches {literal}: {why}"
    ),
}


def _cm(value: float) -> str:
    return f"{value * 100:.1f}"


def _format(template: str, values: dict[str, Any]) -> str:
    """`str.format` with ``{x:cm}``, ``{x:cm2}`` and nested refusals (see `TEMPLATES`)."""
    shown: dict[str, Any] = {}
    for key, value in values.items():
        if isinstance(value, Refusal):
            value = value.detail
        for unit in ("cm2", "cm"):
            field = f"{{{key}:{unit}}}"
            if field in template:
                template = template.replace(field, f"{{{key}__{unit}}}")
                cm = " x ".join(map(_cm, value)) if unit == "cm2" else _cm(value)
                shown[f"{key}__{unit}"] = cm
        shown[key] = value
    if "{margin_note}" in template:
        why = values.get("margin_why", "")
        shown["margin_note"] = f" (+{_cm(values['margin'])} cm {why})" if why else ""
    return template.format(**shown)


def _plain(value: Any) -> Any:
    """A JSON value: floats rounded to 6 digits, pairs as lists, refusals as objects."""
    if isinstance(value, Refusal):
        return value.to_json()
    if isinstance(value, float):
        return round(value, 6)
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return value


class Refusal(NamedTuple):
    """A rule's refusal: its name (a key of `TEMPLATES`) and the values it compared."""

    rule: str
    values: dict[str, Any]

    @property
    def detail(self) -> str:
        """One sentence with the numbers (lengths in cm)."""
        return _format(TEMPLATES[self.rule], self.values)

    def to_json(self) -> dict[str, Any]:
        values = {k: _plain(v) for k, v in self.values.items()}
        return {"rule": self.rule, "detail": self.detail, "values": values}


#: what a ``*_refusal(..., why=False)`` returns for any refusal: the decision needs no reason
REFUSED = Refusal("refused", {})
TEMPLATES["refused"] = "refused (ask with why=True for the reason)"

__all__ = ["REFUSED", "TEMPLATES", "Refusal"]
