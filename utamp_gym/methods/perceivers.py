"""Perceivers that implement `utamp_gym.contract.perceiver.Perceiver`, and loading a user's.

* `BuiltinPerceiver` – the package's geometric perceiver (`utamp_gym.perception.objects`);
* `VlmPerceiver` – the built-in geometry with the attributes a VLM behind an
  OpenAI-compatible endpoint reports (material, mass, robustness, part shapes, food
  surfaces), asked about the overview image of the look (`utamp_gym.methods.vlm_client`);
* `load_perceiver(spec)` – ``builtin``, ``vlm``, a name in the ``utamp_gym.perceivers``
  entry-point group, or ``PACKAGE.MODULE:CLASS`` (built with no arguments);
* `split_method` – ``utamp2-perceived:SPEC`` -> (``utamp2-perceived``, SPEC).
"""

from __future__ import annotations

import difflib
import importlib
import importlib.metadata
import pkgutil
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from utamp_gym.contract.perceiver import PerceivedAttributes, Perceiver, PerceptionRequest
from utamp_gym.errors import EndpointError, UtampError
from utamp_gym.methods.vlm import prompt
from utamp_gym.methods.vlm_client import VlmClient, extract_json, image_part
from utamp_gym.perception.confidence import (
    SIZE_COVERAGE,
    SURFACE_COVERAGE,
    size_readings,
    surface_readings,
)
from utamp_gym.perception.objects import PerceivedObject, perceive_objects
from utamp_gym.scene.catalogue import ROBUSTNESS, SHAPES, ObjectType
from utamp_gym.scene.geometry import SIDES

PERCEIVED = "utamp2-perceived"
ENTRY_POINT_GROUP = "utamp_gym.perceivers"


class PerceiverLoadError(UtampError, ValueError):
    """A perceiver named on the command line could not be loaded."""


def _attributes(obj: PerceivedObject, name: str, orientation: str) -> PerceivedAttributes:
    """The protocol's result for one object the built-in perceiver saw (the only place that
    reads the perceiver's optional ``confidence`` / ``alternatives``: certain if absent).
    The lightest plausible mass over the plausible materials is the last mass alternative
    where it is below the reported one and the others (the perceiver reports the heaviest
    plausible where that decides a lift; a light reading is what the closed loop hopes for
    and then weighs);
    the sizes are offered a reading error narrower and wider (`_readings`)."""
    t = obj.as_type(name, orientation)
    alternatives = dict(getattr(obj, "alternatives", None) or {})
    masses = tuple(alternatives.get("mass", ()))
    if obj.mass_low < min((obj.mass, *masses)):  # the lightest plausible, last
        alternatives["mass"] = (*masses, round(obj.mass_low, 4))
    confidence = dict(getattr(obj, "confidence", None) or {})
    for attribute, (p, alts) in _readings(t).items():  # the sizes' reading errors
        if attribute not in alternatives:
            alternatives[attribute] = alts
            confidence.setdefault(attribute, p)
    return PerceivedAttributes(t, confidence, alternatives)


def _readings(t: ObjectType) -> dict[str, tuple[float, tuple[ObjectType, ...]]]:
    """Attribute -> (confidence, alternatives) of the built-in geometry's reading errors:
    the body's (`confidence.size_readings`) and the top and bottom surfaces'
    (`confidence.surface_readings`, where `t` has any)."""
    out = {"member_size": (SIZE_COVERAGE, size_readings(t))}
    surfaces = surface_readings(t)
    if surfaces:
        out["surface"] = (SURFACE_COVERAGE, surfaces)
    return out


class BuiltinPerceiver:
    """The package's perceiver: geometry fitted to the fused clouds, material from pixels."""

    def perceive(self, request: PerceptionRequest) -> dict[str, PerceivedAttributes]:
        out = {}
        for i, obj in perceive_objects(request.bundle).items():
            name = request.instances.get(i)
            if name is not None:
                out[name] = _attributes(obj, name, request.orientations.get(name, "upright"))
        return out


def overview_png(request: PerceptionRequest) -> bytes:
    """The request's overview image, else the first view with colour, as PNG bytes."""
    if request.rgb_png is not None:
        return request.rgb_png
    import imageio.v3 as iio  # a physics extra

    for view in request.bundle.views:
        if view.rgb is not None:
            return bytes(iio.imwrite("<bytes>", np.asarray(view.rgb), extension=".png"))
    raise EndpointError("the look has no colour image to show the VLM")


class VlmPerceiver:
    """Built-in geometry; material, mass, robustness and part shapes from a VLM (the
    endpoint from ``UTAMP_VLM_BASE_URL`` / ``UTAMP_VLM_MODEL``, `VlmClient.from_env`)."""

    def __init__(self, client: VlmClient | None = None) -> None:
        self.client = client if client is not None else VlmClient.from_env()
        self.geometry = BuiltinPerceiver()

    def perceive(self, request: PerceptionRequest) -> dict[str, PerceivedAttributes]:
        seen = self.geometry.perceive(request)
        system = prompt(
            "attributes_system",
            kinds=", ".join(sorted(request.object_names)),
            robustness=" | ".join(ROBUSTNESS),
            shapes=" | ".join(SHAPES),
        )
        user = [
            {"type": "text", "text": prompt("attributes_request")},
            image_part(overview_png(request)),
        ]
        answer = extract_json(
            self.client.chat(
                [{"role": "system", "content": system}, {"role": "user", "content": user}]
            )
        )
        entries = answer.get("objects")
        if not isinstance(entries, list):
            raise EndpointError("answer: 'objects' is not a list")
        for entry in entries:
            if not isinstance(entry, Mapping):
                continue
            name = str(entry.get("name", "")).strip().lower().replace(" ", "-")
            if name in seen:
                seen[name] = _with_answer(seen[name], entry, name)
        return seen


def _with_answer(
    seen: PerceivedAttributes, entry: Mapping[str, Any], name: str
) -> PerceivedAttributes:
    """`seen` with the attributes a VLM answer entry reports (malformed ones raise), taken as
    certain; the sizes keep the built-in geometry's readings."""
    t = seen.type
    try:
        mass = float(entry.get("mass_kg", t.mass))
    except (TypeError, ValueError):
        raise EndpointError(f"answer: mass_kg of '{name}' is not a number") from None
    robustness = str(entry.get("robustness", t.robustness)).lower()
    if robustness not in ROBUSTNESS or not mass > 0:
        raise EndpointError(f"answer: '{name}' needs mass_kg > 0 and robustness in {ROBUSTNESS}")
    parts = dict(t.parts)
    for side, attrs in dict(entry.get("parts") or {}).items():
        shape = str(dict(attrs).get("shape", "")).lower() if isinstance(attrs, Mapping) else ""
        if side in SIDES and shape in SHAPES:
            food = str(attrs.get("food_surface", False)).lower() == "true"
            parts[side] = parts[side]._replace(shape=shape, food_surface=food)
    material = str(entry.get("material", t.material)).lower()
    answered = t._replace(mass=mass, robustness=robustness, material=material, parts=parts)
    # what the VLM answers is taken as certain; the built-in geometry keeps its reading errors
    kept = {a: r for a, r in _readings(answered).items() if a in seen.alternatives}
    return PerceivedAttributes(
        answered,
        {a: seen.confidence_of(a) for a in kept},
        {a: alts for a, (_, alts) in kept.items()},
    )


BUILTIN: dict[str, Callable[[], Perceiver]] = {"builtin": BuiltinPerceiver, "vlm": VlmPerceiver}


def split_method(method: str) -> tuple[str, str | None]:
    """``utamp2-perceived:SPEC`` -> (``utamp2-perceived``, SPEC); any other -> (it, None)."""
    base, sep, spec = method.partition(":")
    if base == PERCEIVED and sep:
        return base, spec
    return method, None


def _entry_points() -> dict[str, Any]:
    return {ep.name: ep for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)}


def _nearest(name: str, valid: list[str]) -> str:
    close = difflib.get_close_matches(name, valid, n=3, cutoff=0.5)
    return f"; did you mean {', '.join(close)}?" if close else ""


def perceiver_factory(spec: str) -> Callable[[], Any]:
    """The class (or factory) `spec` names (module docstring); raises `PerceiverLoadError`
    naming the module or class, with the nearest valid names."""
    if ":" not in spec:
        if spec in BUILTIN:
            return BUILTIN[spec]
        eps = _entry_points()
        if spec in eps:
            return eps[spec].load()
        valid = sorted({*BUILTIN, *eps})
        raise PerceiverLoadError(
            f"unknown perceiver '{spec}' (not built in, not in the {ENTRY_POINT_GROUP} entry "
            f"points; a class is PACKAGE.MODULE:CLASS){_nearest(spec, valid)} valid: "
            + ", ".join(valid)
        )
    module_name, _, attr = spec.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        missing = exc.name or module_name
        parent = missing.rpartition(".")[0]
        try:
            siblings = [
                f"{parent}.{m}" if parent else m
                for m in _submodules(importlib.import_module(parent) if parent else None)
            ]
        except ImportError:
            siblings = []
        raise PerceiverLoadError(
            f"perceiver module '{module_name}' cannot be imported: no module named "
            f"'{missing}'{_nearest(missing, siblings)}"
        ) from None
    obj = getattr(module, attr, None)
    if obj is None:
        names = [n for n in dir(module) if not n.startswith("_")]
        raise PerceiverLoadError(
            f"perceiver module '{module_name}' has no '{attr}'{_nearest(attr, names)}"
        )
    if not callable(obj):
        raise PerceiverLoadError(f"perceiver '{spec}' is not a class")
    if isinstance(obj, type) and not callable(getattr(obj, "perceive", None)):
        raise _no_perceive(spec)
    return obj


def _no_perceive(spec: str) -> PerceiverLoadError:
    return PerceiverLoadError(
        f"perceiver '{spec}' has no perceive(request) method (utamp_gym.contract.perceiver)"
    )


def _submodules(package: Any) -> list[str]:
    path = None if package is None else getattr(package, "__path__", [])
    return [m.name for m in pkgutil.iter_modules(path)]


def load_perceiver(spec: str | None) -> Perceiver:
    """A perceiver instance for `spec` (None: the built-in one); it must have `perceive`."""
    if spec is None or spec == "builtin":
        return BuiltinPerceiver()
    made = perceiver_factory(spec)()
    if not isinstance(made, Perceiver):
        raise _no_perceive(spec)
    return made


def check_perceiver(spec: str) -> None:
    """Raise `PerceiverLoadError` if `spec` does not name a loadable perceiver (nothing is
    built: a VLM perceiver would need its endpoint)."""
    perceiver_factory(spec)


__all__ = [
    "BUILTIN",
    "ENTRY_POINT_GROUP",
    "BuiltinPerceiver",
    "PerceiverLoadError",
    "VlmPerceiver",
    "check_perceiver",
    "load_perceiver",
    "perceiver_factory",
    "split_method",
]
