"""Material from appearance, and the mass and robustness that follow from it.

**Appearance features** (`appearance_features`) come from an object's pixels in all views:
its chromaticity (colour with the brightness divided out: under white light the shading
scales all three channels alike), its median saturation and brightness, and its highlights
(how far the brightest pixels rise above the median, how white they are, how many there
are) — the finish: glazed ceramic and steel shine, wood and cardboard do not; and the
spread of its colour where something shows through it (glass is translucent).

**The classifier** (`MaterialModel`) is a Gaussian per material over those features (plain
numpy), trained on rendered instances whose colours and finishes were drawn from each
material's palette (`utamp_gym.scene.materials`), by `benchmarks/material_model.py`, which
writes `assets/perception/material_model.json` and measures it against scikit-learn's
classifiers (docs/perception.md). Without the file, the nearest palette colour in
chromaticity decides.

**Mass** (`estimate_mass`) is volume x density: solid pieces (carved wood: `Material.wall`
is None) fill their visible envelope less what is seen to be hollow; the others are shells
of their material's typical wall thickness over their outer surface. The density is the
*upper* end of the material's range: the rules use mass only to ask whether the robot can
carry an object and whether a support bears it, and a perceiver should not promise either
for what may be too heavy. **Robustness** is the material's.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from utamp_gym.scene.materials import MATERIALS, hex_rgba, material

FEATURES = (
    "chroma_r",
    "chroma_g",
    "chroma_b",
    "saturation",
    "value",
    "highlight_rise",
    "highlight_whiteness",
    "highlight_share",
    "chroma_spread",
)
MODEL_FILE = ("perception", "material_model.json")


def _hsv(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Saturation and value of (N, 3) colours in [0, 1]."""
    mx, mn = rgb.max(axis=1), rgb.min(axis=1)
    sat = np.where(mx > 1e-6, (mx - mn) / np.maximum(mx, 1e-6), 0.0)
    return sat, mx


def appearance_features(colours: np.ndarray) -> np.ndarray:
    """The `FEATURES` of an object's pixel colours (N, 3) uint8 (module docstring)."""
    rgb = np.asarray(colours, dtype=float) / 255.0
    if len(rgb) < 5:
        return np.full(len(FEATURES), np.nan)
    sat, val = _hsv(rgb)
    lo, hi = np.percentile(val, [20, 80])
    body = rgb[(val >= lo) & (val <= hi)]
    if len(body) < 3:
        body = rgb
    total = body.sum(axis=1, keepdims=True)
    chroma = body / np.maximum(total, 1e-6)
    med = np.median(chroma, axis=0)
    spread = float(np.median(np.abs(chroma - med).sum(axis=1)))
    v50, v97 = np.percentile(val, [50, 97])
    bright = val >= v97
    return np.array(
        [
            *med,
            float(np.median(sat)),
            float(v50),
            float(v97 - v50),
            float(1.0 - np.median(sat[bright])) if bright.any() else 0.0,
            float(np.mean(val > v50 + 0.2)),
            spread,
        ]
    )


@dataclass(frozen=True)
class MaterialEstimate:
    """The most likely material and the posterior of every material considered."""

    name: str
    posterior: dict[str, float]


class MaterialModel:
    """Gaussian class-conditional model (diagonal covariance) over `FEATURES`."""

    def __init__(self, names: list[str], means: np.ndarray, stds: np.ndarray) -> None:
        self.names, self.means, self.stds = names, np.asarray(means), np.asarray(stds)

    @classmethod
    def fit(cls, features: np.ndarray, labels: list[str], floor: float = 0.01) -> MaterialModel:
        names = sorted(set(labels))
        lab = np.asarray(labels)
        means = np.array([features[lab == n].mean(axis=0) for n in names])
        stds = np.array([features[lab == n].std(axis=0) + floor for n in names])
        return cls(names, means, stds)

    def to_json(self) -> dict[str, object]:
        return {
            "features": list(FEATURES),
            "materials": self.names,
            "means": np.round(self.means, 6).tolist(),
            "stds": np.round(self.stds, 6).tolist(),
        }

    @classmethod
    def from_json(cls, data: dict[str, object]) -> MaterialModel:
        if list(data["features"]) != list(FEATURES):  # type: ignore[call-overload]
            raise ValueError("material model was trained on other features")
        return cls(list(data["materials"]), np.asarray(data["means"]), np.asarray(data["stds"]))  # type: ignore[call-overload, arg-type]

    def log_likelihood(self, x: np.ndarray) -> np.ndarray:
        z = (x[None, :] - self.means) / self.stds
        return -0.5 * (z**2).sum(axis=1) - np.log(self.stds).sum(axis=1)

    def classify(self, x: np.ndarray) -> MaterialEstimate:
        ll = self.log_likelihood(x)
        p = np.exp(ll - ll.max())
        p /= p.sum()
        post = {n: float(v) for n, v in zip(self.names, p, strict=True)}
        return MaterialEstimate(self.names[int(np.argmax(p))], post)


@lru_cache(maxsize=1)
def packaged_model() -> MaterialModel | None:
    """The trained model shipped with the package, or None if there is none."""
    from utamp_gym.errors import AssetError
    from utamp_gym.resources import asset_path

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
    colours: np.ndarray | None, model: MaterialModel | None = None
) -> MaterialEstimate:
    """Material of an object from its pixel colours (the packaged model unless given)."""
    if colours is None or len(colours) < 5:
        return MaterialEstimate("default", {"default": 1.0})
    x = appearance_features(colours)
    model = model if model is not None else packaged_model()
    return model.classify(x) if model is not None else nearest_palette(x)


def estimate_mass(material_name: str, solid_volume: float, area: float) -> tuple[float, float]:
    """(mass, lightest plausible mass) in kg of a piece of `material_name` (module docstring):
    the heaviest plausible mass is what the perceived type reports."""
    m = material(material_name)
    volume = solid_volume if m.wall is None else min(solid_volume, area * m.wall)
    lo, hi = m.density_range
    return float(volume * hi), float(volume * lo)


__all__ = [
    "FEATURES",
    "MaterialEstimate",
    "MaterialModel",
    "appearance_features",
    "classify_material",
    "estimate_mass",
    "nearest_palette",
    "packaged_model",
]
