"""Material from appearance, and the mass and robustness that follow from it.

**Appearance features** (`appearance_features`) come from an object's pixels in all views:
its chromaticity (colour with the brightness divided out: under white light the shading
scales all three channels alike), its median saturation and brightness, and its highlights
(how far the brightest pixels rise above the median, how white they are, how many there
are) — the finish: glazed ceramic and steel shine, wood and cardboard do not; and the
spread of its colour where something shows through it (glass is translucent).

**The classifier** (`MaterialModel`) is a mixture of Gaussians over those features (plain
numpy; one component per palette colour of each material), trained on rendered instances
whose colours and finishes were drawn from each material's palette
(`utamp_gym.scene.materials`) independently of their shape, times a prior of the material
given the object's coarse shape (`shape_class`: a rimmed tray is rarely cardboard, a
closed box often is), counted over the packaged catalogues with `PRIOR_ALPHA` pseudo-counts
per material — the context a person (or a VLM) uses where colour and finish are alike, as
those of wood and cardboard are. `benchmarks/material_model.py` trains it, writes
`assets/perception/material_model.json` and measures it against scikit-learn's classifiers
(docs/perception.md). Without the file, the nearest palette colour in chromaticity
decides.

**Mass** (`estimate_mass`) is volume x density: solid pieces (carved wood: `Material.wall`
is None) fill their visible envelope less what is seen to be hollow; the others are shells
of their material's typical wall thickness over their outer surface. The density is the
material's nominal one (`Material.density`), the middle of what real pieces span: the rules
ask of mass whether the robot can carry an object, whether a support bears it and whether
the fingers hold the moment of its weight about a grasp (`affordances.hand`), and the upper
end of the range made a 0.6 kg wooden board with a handle weigh 1.2 kg, too heavy to be held
by its handle, so that no plan moved it. The lightest and heaviest plausible masses are
kept beside it (the heaviest decides whether a rimmed object with handles may be too heavy
to lift, so that its rims are offered as grips, `objects._edges`).
**Robustness** is the material's.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from utamp_gym.errors import AssetError
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.materials import MATERIALS, hex_rgba, material

FEATURES = (
    "chroma_r",
    "chroma_g",
    "chroma_b",
    "saturation",
    "value",
    "top_gain",
    "top_white",
    "low_peak",
    "low_whiteness",
    "chroma_spread",
)
#: camera optical axes pointing down steeper than this look from above; flatter than
#: `LOW_AXIS_Z` look along the table (their own light then strikes sides head-on)
TOP_AXIS_Z, LOW_AXIS_Z = -0.85, -0.3
MODEL_FILE = ("perception", "material_model.json")


def _hsv(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Saturation and value of (N, 3) colours in [0, 1]."""
    mx, mn = rgb.max(axis=1), rgb.min(axis=1)
    sat = np.where(mx > 1e-6, (mx - mn) / np.maximum(mx, 1e-6), 0.0)
    return sat, mx


def appearance_features(views: list[tuple[float, np.ndarray]]) -> np.ndarray:
    """The `FEATURES` of an object from its pixels: (optical axis z, colours (N, 3) uint8)
    per view (module docstring). The colour comes from the views that do not look from
    above (from above, the sun's reflection washes shiny tops out); the finish from how
    much brighter and whiter the object looks from above than from the side, and from the
    peak of the highlight the low cameras' own light puts on faces turned to them."""
    top = [c for z, c in views if z < TOP_AXIS_Z and len(c)]
    low = [c for z, c in views if z > LOW_AXIS_Z and len(c)]
    side = [c for z, c in views if z >= TOP_AXIS_Z and len(c)]
    if not side:
        side = top
    if not side or sum(len(c) for c in side) < 5:
        return np.full(len(FEATURES), np.nan)
    rgb = np.concatenate(side).astype(float) / 255.0
    sat, val = _hsv(rgb)
    lo, hi = np.percentile(val, [20, 80])
    body = rgb[(val >= lo) & (val <= hi)]
    if len(body) < 3:
        body = rgb
    chroma = body / np.maximum(body.sum(axis=1, keepdims=True), 1e-6)
    med = np.median(chroma, axis=0)
    spread = float(np.median(np.abs(chroma - med).sum(axis=1)))
    v50 = float(np.median(val))
    top_gain = top_white = 0.0
    if top:
        t = np.concatenate(top).astype(float) / 255.0
        ts, tv = _hsv(t)
        top_gain = float(np.median(tv)) - v50
        top_white = float(np.mean((tv > 0.93) & (ts < 0.2)))
    low_peak = low_white = 0.0
    if low:
        lw = np.concatenate(low).astype(float) / 255.0
        ls, lv = _hsv(lw)
        peak = lv >= np.percentile(lv, 99)
        low_peak = float(np.percentile(lv, 99.5) - np.median(lv))
        low_white = float(1.0 - np.median(ls[peak]))
    return np.array(
        [*med, float(np.median(sat)), v50, top_gain, top_white, low_peak, low_white, spread]
    )


@dataclass(frozen=True)
class MaterialEstimate:
    """The most likely material and the posterior of every material considered."""

    name: str
    posterior: dict[str, float]


class MaterialModel:
    """A mixture of Gaussians (diagonal covariance) over `FEATURES`: one component per
    palette colour of each material (a material's colours are far apart), each weighted by
    how many training objects it explained."""

    def __init__(
        self,
        materials: list[str],
        means: np.ndarray,
        stds: np.ndarray,
        weights: np.ndarray,
        prior: dict[str, dict[str, float]] | None = None,
        temperature: float = 1.0,
    ) -> None:
        self.materials = list(materials)  # the material of each component
        self.means, self.stds = np.asarray(means), np.asarray(stds)
        self.weights = np.asarray(weights, dtype=float)
        self.prior = prior or {}  # shape class -> material -> probability
        #: the appearance log-likelihood is divided by it: correlated features would
        #: otherwise count as independent evidence (calibrated on held-out renders)
        self.temperature = float(temperature)

    @classmethod
    def fit(cls, features: np.ndarray, labels: list[str], floor: float = 0.004) -> MaterialModel:
        """One component per (material, nearest palette colour) of the training objects."""
        comp_of = [(lab, _nearest_colour(lab, x)) for x, lab in zip(features, labels, strict=True)]
        keys = sorted(set(comp_of))
        pooled = {lab: features[[c[0] == lab for c in comp_of]].std(axis=0) for lab in set(labels)}
        mats, means, stds, weights = [], [], [], []
        for key in keys:
            sel = np.array([c == key for c in comp_of])
            x = features[sel]
            std = x.std(axis=0) if len(x) >= 5 else pooled[key[0]]
            mats.append(key[0])
            means.append(x.mean(axis=0))
            stds.append(np.maximum(std, floor))
            weights.append(len(x))
        return cls(mats, np.array(means), np.array(stds), np.array(weights))

    def to_json(self) -> dict[str, object]:
        return {
            "features": list(FEATURES),
            "temperature": round(self.temperature, 4),
            "prior": {
                c: {m: round(p, 4) for m, p in sorted(ps.items())}
                for c, ps in sorted(self.prior.items())
            },
            "components": [
                {"material": m, "weight": float(w), "mean": np.round(mu, 6).tolist(),
                 "std": np.round(sd, 6).tolist()}
                for m, w, mu, sd in zip(self.materials, self.weights, self.means, self.stds,
                                        strict=True)
            ],
        }  # fmt: skip

    @classmethod
    def from_json(cls, data: dict[str, object]) -> MaterialModel:
        if list(data["features"]) != list(FEATURES):  # type: ignore[call-overload]
            raise ValueError("material model was trained on other features")
        comps = data["components"]
        return cls(
            [c["material"] for c in comps],  # type: ignore[union-attr, index]
            np.array([c["mean"] for c in comps]),  # type: ignore[union-attr, index]
            np.array([c["std"] for c in comps]),  # type: ignore[union-attr, index]
            np.array([c["weight"] for c in comps]),  # type: ignore[union-attr, index]
            data.get("prior"),  # type: ignore[arg-type]
            float(data.get("temperature", 1.0)),  # type: ignore[arg-type]
        )

    def with_prior(
        self, prior: dict[str, dict[str, float]], temperature: float | None = None
    ) -> MaterialModel:
        t = self.temperature if temperature is None else temperature
        return MaterialModel(self.materials, self.means, self.stds, self.weights, prior, t)

    def calibrated(self, features: np.ndarray, labels: list[str]) -> MaterialModel:
        """This model with the temperature that best predicts `labels` (held-out objects:
        the lowest mean negative log posterior of the true material)."""
        best, best_nll = 1.0, math.inf
        for t in (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0):
            m = self.with_prior(self.prior, t)
            nll = -np.mean(
                [
                    math.log(max(m.classify(x).posterior.get(y, 0.0), 1e-12))
                    for x, y in zip(features, labels, strict=True)
                ]
            )
            if nll < best_nll:
                best, best_nll = t, nll
        return self.with_prior(self.prior, best)

    def classify(self, x: np.ndarray, shape: str | None = None) -> MaterialEstimate:
        """Posterior over materials of appearance `x` on an object of shape class `shape`."""
        z = (x[None, :] - self.means) / self.stds
        ll = -0.5 * (z**2).sum(axis=1) - np.log(self.stds).sum(axis=1)
        ll = ll / self.temperature + np.log(self.weights)
        p = np.exp(ll - ll.max())
        post: dict[str, float] = {}
        for m, v in zip(self.materials, p, strict=True):
            post[m] = post.get(m, 0.0) + float(v)
        total = sum(post.values())
        post = {m: v / total for m, v in post.items()}
        context = self.prior.get(shape or "", {})
        if context:
            post = {m: v * context.get(m, min(context.values())) for m, v in post.items()}
        total = sum(post.values())
        post = {m: v / total for m, v in post.items()}
        return MaterialEstimate(max(post, key=post.__getitem__), post)


def _nearest_colour(material_name: str, x: np.ndarray) -> int:
    """Index of the palette colour of `material_name` nearest to features `x` (chroma)."""
    best, best_d = 0, math.inf
    for k, c in enumerate(material(material_name).palette):
        rgb = np.asarray(hex_rgba(c)[:3])
        d = float(np.abs(rgb / max(rgb.sum(), 1e-6) - x[:3]).sum())
        if d < best_d:
            best, best_d = k, d
    return best


@lru_cache(maxsize=1)
def packaged_model() -> MaterialModel | None:
    """The trained model shipped with the package, or None if there is none."""
    try:
        path = Path(asset_path(*MODEL_FILE))
    except AssetError:
        return None
    return MaterialModel.from_json(json.loads(path.read_text()))


def nearest_palette(x: np.ndarray) -> MaterialEstimate:
    """The material whose palette has the colour nearest in chromaticity (no finish)."""
    best: dict[str, float] = {}
    for m in MATERIALS.values():
        for c in m.palette:
            rgb = np.asarray(hex_rgba(c)[:3])
            chroma = rgb / max(rgb.sum(), 1e-6)
            d = float(np.abs(chroma - x[:3]).sum())
            best[m.name] = min(best.get(m.name, math.inf), d)
    name = min(best, key=best.__getitem__)
    w = {n: math.exp(-d / 0.02) for n, d in best.items()}
    total = sum(w.values())
    return MaterialEstimate(name, {n: v / total for n, v in w.items()})


def classify_material(
    views: list[tuple[float, np.ndarray]],
    shape: str | None = None,
    model: MaterialModel | None = None,
) -> MaterialEstimate:
    """Material of an object from its pixels per view (see `appearance_features`) and its
    shape class (`shape_class`), with the packaged model unless `model` is given."""
    if sum(len(c) for _, c in views) < 5:
        return MaterialEstimate("default", {"default": 1.0})
    x = appearance_features(views)
    model = model if model is not None else packaged_model()
    return model.classify(x, shape) if model is not None else nearest_palette(x)


#: pseudo-count per material and shape class: a small one trusts the catalogues' pairing of
#: shapes and materials (measured in docs/perception.md, with and without it)
PRIOR_ALPHA = 0.1
SHAPE_CLASSES = ("necked", "vessel", "dish", "well", "slab", "closed-box", "closed-round")


def shape_class(t: ObjectType) -> str:
    """Coarse shape of a catalogue type (perceived or declared), for the material prior."""
    on, body = t.parts["on"], t.body
    if on.shape == "pointy" and body.box.max[2] < t.bbox.max[2] - 1e-6:
        return "necked"
    if on.shape == "open":
        return "vessel"
    if on.shape == "concave":
        return "dish"
    if on.shape == "flat" and on.height is not None and on.height < body.box.max[2] - 0.003:
        return "well"
    if body.geom == "cylinder":
        return "closed-round"
    return "slab" if body.box.size[2] < 0.055 else "closed-box"


def shape_prior(types: list[ObjectType], alpha: float = PRIOR_ALPHA) -> dict[str, dict[str, float]]:
    """P(material | shape class) counted over `types` with `alpha` pseudo-counts."""
    names = sorted(MATERIALS)
    counts = {c: dict.fromkeys(names, alpha) for c in SHAPE_CLASSES}
    for t in types:
        if t.movable and t.material in MATERIALS:
            counts[shape_class(t)][t.material] += 1.0
    return {c: {m: v / sum(ms.values()) for m, v in ms.items()} for c, ms in counts.items()}


def estimate_mass(
    material_name: str, solid_volume: float, area: float
) -> tuple[float, float, float]:
    """(mass, lightest, heaviest plausible mass) in kg of a piece of `material_name` (module
    docstring): the mass at the material's nominal density is what the perceived type
    reports."""
    m = material(material_name)
    volume = solid_volume if m.wall is None else min(solid_volume, area * m.wall)
    lo, hi = m.density_range
    return float(volume * m.density), float(volume * lo), float(volume * hi)


__all__ = [
    "FEATURES",
    "MaterialEstimate",
    "MaterialModel",
    "appearance_features",
    "classify_material",
    "estimate_mass",
    "nearest_palette",
    "packaged_model",
    "shape_class",
    "shape_prior",
]
