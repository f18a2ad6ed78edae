"""How sure the perceiver is of each attribute it estimates, and what else it might be.

Every `PerceivedObject` carries `confidence` (attribute -> probability that the chosen value
is right) and `alternatives` (attribute -> the other plausible values, most likely first),
with keys from `utamp_gym.methods.attributes.ATTRIBUTES`:

* **material**: the classifier's posterior of the chosen material (`MaterialEstimate`);
  the alternatives are the other materials at least `ALT_MIN` likely;
* **robustness**: the posterior summed over the materials of the chosen robustness; the
  alternatives are the other robustness classes;
* **mass**: judged as its *class* at the rules' thresholds (`MASS_BOUNDS`: the edge-pinch
  limit, the rim-pinch limit, the lift limit, the sturdy load capacity): for each material,
  the share of its density range (uniform) whose mass falls into each class, weighted by
  the material's posterior. The alternatives are masses (kg), one per other plausible
  class, most likely first: the heaviest plausible mass in that class (planning with it
  promises what holds for the whole class);
* **members**: from the geometry alone: how much of the body's top was hidden under other
  objects (`SeenShape.covered`) — what hides a handle or a neck;
* **member_size**: the body is read within `SIZE_ERROR` a side with probability
  `SIZE_COVERAGE` (measured on procedural-v1/train by `benchmarks/perceiver_train.py`); the
  alternatives are the type read that much narrower and that much wider (`size_readings`).
  Neither promises more than the other — a narrower body fits into the hand and onto more
  supports, a wider one carries more — so hoping believes the facts of either
  (`utamp_gym.methods.doubt.hoped_facts`);
* **surface**: likewise the top and bottom surfaces (a flat face, a well, an opening), read
  within `SURFACE_ERROR` a side with probability `SURFACE_COVERAGE`; the alternatives are
  the type with them read that much narrower and wider (`surface_readings`).

The raw values are then mapped through monotone calibration maps fitted on
procedural-v1/train renders (`benchmarks/perceiver_train.py`, isotonic regression of
"the value was right" on the raw confidence), shipped as
``assets/perception/confidence_calibration.json``; without the file the raw values stand.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Mapping, Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np

from utamp_gym.errors import AssetError
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import MIN_EXTENT, ObjectType
from utamp_gym.scene.geometry import Box
from utamp_gym.scene.materials import material

#: kg: the mass thresholds the rules use (affordances.rules EDGE_LIFT_LIMIT, affordances.rim
#: RIM_LIFT_LIMIT, rules PAYLOAD x LIFT_FRACTION, LOAD_CAPACITY["sturdy"]); a test checks them
MASS_BOUNDS = (0.5, 1.1, 1.5, 3.0)
ALT_MIN = 0.02  # the least probability of a value offered as an alternative
CALIBRATION_FILE = ("perception", "confidence_calibration.json")
#: the share of body readings within `SIZE_ERROR` a side of the declared size
SIZE_COVERAGE = 0.9
#: m a side: the `SIZE_COVERAGE` quantile of the body's reading error on the even-numbered
#: procedural-v1/train scenes, rounded up to 0.1 mm (docs/results/perceiver-train.json
#: ``size_error``; a test checks it)
SIZE_ERROR = 0.0007
#: the share of top and bottom surface readings (a flat face, a well, an opening) within
#: `SURFACE_ERROR` a side of the declared size
SURFACE_COVERAGE = 0.9
#: m a side: the `SURFACE_COVERAGE` quantile of the surfaces' reading error on the
#: even-numbered procedural-v1/train scenes, rounded up to 0.1 mm
#: (docs/results/perceiver-train.json ``surface_error``; a test checks it)
SURFACE_ERROR = 0.0012


def mass_class(mass: float) -> int:
    """Index of the class of `mass` between the rules' thresholds (`MASS_BOUNDS`)."""
    return int(np.searchsorted(MASS_BOUNDS, mass, side="left"))


def _class_shares(low: float, high: float) -> np.ndarray:
    """Share of a uniform mass range [low, high] in each class."""
    edges = [low, *[b for b in MASS_BOUNDS if low < b < high], high]
    out = np.zeros(len(MASS_BOUNDS) + 1)
    if high - low <= 1e-12:
        out[mass_class(low)] = 1.0
        return out
    for a, b in itertools.pairwise(edges):
        out[mass_class((a + b) / 2)] += (b - a) / (high - low)
    return out


def mass_volume(material_name: str, solid_volume: float, area: float) -> float:
    """The volume (m^3) of material in a piece (`material.estimate_mass`'s rule)."""
    m = material(material_name)
    return solid_volume if m.wall is None else min(solid_volume, area * m.wall)


def mass_classes(
    posterior: Mapping[str, float], solid_volume: float, area: float
) -> tuple[np.ndarray, np.ndarray]:
    """(P(class), heaviest plausible mass per class) over the materials' posterior."""
    probs = np.zeros(len(MASS_BOUNDS) + 1)
    heaviest = np.zeros(len(MASS_BOUNDS) + 1)
    for name, p in posterior.items():
        vol = mass_volume(name, solid_volume, area)
        lo, hi = (d * vol for d in material(name).density_range)
        shares = _class_shares(lo, hi)
        probs += p * shares
        for c in np.nonzero(shares > 0)[0]:
            top = MASS_BOUNDS[c] if c < len(MASS_BOUNDS) else np.inf
            heaviest[c] = max(heaviest[c], min(hi, top))
    return probs / max(probs.sum(), 1e-12), heaviest


def raw_confidences(
    posterior: Mapping[str, float],
    chosen_material: str,
    mass: float,
    solid_volume: float,
    area: float,
    covered: float,
) -> tuple[dict[str, float], dict[str, tuple]]:
    """Uncalibrated (confidence, alternatives) of one object (module docstring)."""
    conf: dict[str, float] = {}
    alts: dict[str, tuple] = {}
    ranked = sorted(posterior.items(), key=lambda kv: -kv[1])
    conf["material"] = float(posterior.get(chosen_material, 0.0))
    alts["material"] = tuple(m for m, p in ranked if m != chosen_material and p >= ALT_MIN)
    rob: dict[str, float] = {}
    for m, p in posterior.items():
        r = material(m).robustness
        rob[r] = rob.get(r, 0.0) + p
    chosen_rob = material(chosen_material).robustness
    conf["robustness"] = float(rob.get(chosen_rob, 0.0))
    alts["robustness"] = tuple(
        r for r, p in sorted(rob.items(), key=lambda kv: -kv[1]) if r != chosen_rob and p >= ALT_MIN
    )
    probs, heaviest = mass_classes(posterior, solid_volume, area)
    c = mass_class(mass)
    conf["mass"] = float(probs[c])
    order = [k for k in np.argsort(-probs, kind="stable") if k != c and probs[k] >= ALT_MIN]
    alts["mass"] = tuple(round(float(heaviest[k]), 4) for k in order)
    conf["members"] = float(np.clip(1.0 - covered, 0.0, 1.0))
    alts["members"] = ()
    return conf, alts


def size_readings(t: ObjectType, error: float = SIZE_ERROR) -> tuple[ObjectType, ObjectType]:
    """`t` with its body read `error` narrower, and wider, on every side along x and y (the
    parts' declared sizes with it); a side too thin to narrow stays."""
    return _widened(t, -error), _widened(t, error)


def surface_readings(t: ObjectType, error: float = SURFACE_ERROR) -> tuple[ObjectType, ...]:
    """`t` with its sized top and bottom surfaces (`PartAttrs.size`: a flat face, a well,
    an opening) read `error` narrower, and wider, on every side; () if it has none. The
    body stays: a well's rim or an opening's wall is read apart from the body's outline."""
    sized = [p for p in ("on", "under") if t.parts[p].size is not None]
    if not sized:
        return ()

    def read(d: float) -> ObjectType:
        parts = dict(t.parts)
        for p in sized:
            w, h = t.parts[p].size  # type: ignore[misc]
            size = (max(w + 2 * d, MIN_EXTENT), max(h + 2 * d, MIN_EXTENT))
            parts[p] = parts[p]._replace(size=(round(size[0], 6), round(size[1], 6)))
        return t._replace(parts=parts)

    return read(-error), read(error)


def _widened(t: ObjectType, d: float) -> ObjectType:
    body = t.body
    lo, hi = body.box.min, body.box.max
    if min(hi[0] - lo[0], hi[1] - lo[1]) + 2 * d < 2 * MIN_EXTENT:
        return t
    box = Box((lo[0] - d, lo[1] - d, lo[2]), (hi[0] + d, hi[1] + d, hi[2]))
    parts = {
        p: a if a.size is None else a._replace(size=(a.size[0] + 2 * d, a.size[1] + 2 * d))
        for p, a in t.parts.items()
    }
    return t._replace(members={**t.members, body.name: body._replace(box=box)}, parts=parts)


class Calibration:
    """Monotone maps raw confidence -> probability of being right, one per attribute
    (piecewise linear through isotonic-regression knots)."""

    def __init__(self, knots: Mapping[str, tuple[Sequence[float], Sequence[float]]]) -> None:
        self.knots = {
            a: (np.asarray(x, float), np.asarray(y, float)) for a, (x, y) in knots.items()
        }

    def __call__(self, attribute: str, raw: float) -> float:
        if attribute not in self.knots:
            return raw
        x, y = self.knots[attribute]
        return float(np.interp(raw, x, y))

    def apply(self, conf: Mapping[str, float]) -> dict[str, float]:
        return {a: round(self(a, v), 4) for a, v in conf.items()}

    @classmethod
    def fit(cls, samples: Mapping[str, tuple[Sequence[float], Sequence[float]]]) -> Calibration:
        """Isotonic fit of correctness (0/1) on raw confidence per attribute."""
        return cls({a: isotonic_knots(x, y) for a, (x, y) in samples.items() if len(x)})

    def to_json(self) -> dict[str, object]:
        return {a: {"raw": x.round(4).tolist(), "calibrated": y.round(4).tolist()}
                for a, (x, y) in sorted(self.knots.items())}  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping[str, Mapping[str, Sequence[float]]]) -> Calibration:
        return cls({a: (d["raw"], d["calibrated"]) for a, d in data.items()})


def isotonic_knots(
    raw: Sequence[float], correct: Sequence[float], prior: float = 1.0
) -> tuple[list[float], list[float]]:
    """Pool-adjacent-violators: a non-decreasing step fit of `correct` on `raw`, smoothed
    by `prior` pseudo-observations at the pooled mean (so that a bin of a few samples is
    not called certain); one knot per pooled block at its mean raw value."""
    order = np.argsort(raw, kind="stable")
    x = np.asarray(raw, float)[order]
    y = np.asarray(correct, float)[order]
    base = float(y.mean())
    blocks: list[list[float]] = []  # [sum_y, n, sum_x]
    for xi, yi in zip(x, y, strict=True):
        blocks.append([yi, 1.0, xi])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] >= blocks[-1][0] / blocks[-1][1]:
            s, n, sx = blocks.pop()
            blocks[-1][0] += s
            blocks[-1][1] += n
            blocks[-1][2] += sx
    kx = [b[2] / b[1] for b in blocks]
    ky = [(b[0] + prior * base) / (b[1] + prior) for b in blocks]
    ky = list(np.maximum.accumulate(ky))
    return kx, ky


@lru_cache(maxsize=1)
def packaged_calibration() -> Calibration | None:
    """The calibration shipped with the package, or None if there is none."""
    try:
        path = Path(asset_path(*CALIBRATION_FILE))
    except AssetError:
        return None
    return Calibration.from_json(json.loads(path.read_text()))


__all__ = [
    "ALT_MIN",
    "MASS_BOUNDS",
    "SIZE_COVERAGE",
    "SIZE_ERROR",
    "SURFACE_COVERAGE",
    "SURFACE_ERROR",
    "Calibration",
    "isotonic_knots",
    "mass_class",
    "mass_classes",
    "packaged_calibration",
    "raw_confidences",
    "size_readings",
    "surface_readings",
]
