"""A learned attribute model: material, mass class and mass from the perceiver's own measurements.

The hand-built pipeline (`perception.material`) reads material from appearance alone (a
mixture of Gaussians over colour and finish, times a shape prior) and mass as volume x the
material's nominal density. Both were fitted to the objects they were developed on. This
model learns the same attributes from everything the perceiver measures of an object
(`measurements`): its appearance features and the mixture's posterior, its coarse shape
class, the fitted body's size and geometry, the seen top (open, concave, flat, rim, floor),
its volume, outer surface and the wall thickness they imply, and its members.

Three heads, plain numpy at run time (`AttributeModel`):

* **material**: three experts pooled in their logits, then temperature-scaled: a multinomial
  logistic regression over all of `features`, one over the appearance columns alone (the
  first `N_APPEARANCE`: colour, finish and the hand-built posterior), and the hand-built
  mixture's own log posterior (`AttributeModel.pool`, `AttributeModel.handbuilt`).
  Geometry tells a train family's material well and an unseen family's badly (the model
  learns the family, which does not carry over); appearance carries over. The pooling is
  chosen on held-out objects of train by its accuracy, averaged over even/odd halves
  (families seen), leave-one-family-out folds (families unseen) and train scenes never
  fitted; the temperature by the negative log-likelihood over all of them;
* **mass class** at the rules' thresholds (`confidence.MASS_BOUNDS`): multinomial logistic
  regression, temperature-scaled likewise;
* **mass** (kg): ridge regression of log mass, clamped into the predicted class.

Where cross-validation on train finds the hand-built volume x density rule reads the mass
class better than the two mass heads (``mass_head: rule``), the perceiver keeps that rule,
applied to the learned material, with its own confidences.

Robustness is the material's (the posterior summed over the materials of each class).
`benchmarks/attribute_model.py` renders procedural-v1/train, trains the model (held-out
train objects choose its settings: see the material head above) and ships it as
``assets/perception/attribute_model.json``; without the file the hand-built pipeline stands.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from utamp_gym.errors import AssetError
from utamp_gym.perception.confidence import ALT_MIN, MASS_BOUNDS, mass_class
from utamp_gym.perception.material import FEATURES, SHAPE_CLASSES
from utamp_gym.perception.seen import SeenShape
from utamp_gym.resources import asset_path
from utamp_gym.scene.materials import MATERIALS

MODEL_FILE = ("perception", "attribute_model.json")
MATERIAL_NAMES = tuple(sorted(MATERIALS))
TOP_SHAPES = ("open", "concave", "flat", "pointy")
N_MASS_CLASSES = len(MASS_BOUNDS) + 1
#: the leading columns of `features` that describe appearance only (colour and finish
#: features, the missing-pixels flag, the hand-built material posterior)
N_APPEARANCE = len(FEATURES) + 1 + len(MATERIAL_NAMES)
#: the columns of `features` that hold the hand-built mixture's log posterior
POSTERIOR = slice(len(FEATURES) + 1, N_APPEARANCE)


def measurements(
    shape: SeenShape,
    appearance: np.ndarray,
    posterior: Mapping[str, float],
    shape_cls: str,
    solid_volume: float,
    shell_area: float,
) -> dict[str, float | str]:
    """What the perceiver measured of one object, by name (the model's raw input)."""
    size = sorted(float(s) for s in shape.body.box.size)
    top = shape.top
    out: dict[str, float | str] = {f: float(v) for f, v in zip(FEATURES, appearance, strict=True)}
    out.update({f"post_{m}": float(posterior.get(m, 0.0)) for m in MATERIAL_NAMES})
    out.update({
        "shape_class": shape_cls, "top_shape": top.shape,
        "cylinder": float(shape.body.geom == "cylinder"),
        "size_0": size[0], "size_1": size[1], "size_2": size[2],
        "height": float(shape.body.box.size[2]), "top_rim": float(top.rim),
        "top_floor": float(top.floor), "top_visible": float(top.visible),
        "covered": float(shape.covered), "flare": float(shape.flare),
        "n_members": float(len(shape.members)), "volume": float(solid_volume),
        "area": float(shell_area), "envelope": float(np.prod(shape.body.box.size)),
        "members_volume": float(sum(np.prod(m.box.size) for m in shape.members)),
    })  # fmt: skip
    return out


def features(m: Mapping[str, float | str]) -> np.ndarray:
    """The model's feature vector of measurements `m` (`measurements`)."""
    app = [float(m[f]) for f in FEATURES]
    missing = float(any(math.isnan(v) for v in app))
    app = [0.0 if math.isnan(v) else v for v in app]
    post = [math.log(max(float(m[f"post_{n}"]), 1e-6)) for n in MATERIAL_NAMES]
    shape = [float(m["shape_class"] == c) for c in SHAPE_CLASSES]
    top = [float(m["top_shape"] == t) for t in TOP_SHAPES]
    sizes = [float(m[k]) for k in ("size_0", "size_1", "size_2")]
    logs = [math.log(max(s, 1e-3)) for s in sizes]
    vol, area = max(float(m["volume"]), 1e-7), max(float(m["area"]), 1e-5)
    env = max(float(m["envelope"]), 1e-7)
    geo = [
        math.log(vol), math.log(area), math.log(vol / area), vol / env,
        math.log(env), float(m["cylinder"]), float(m["top_rim"]),
        float(m["top_floor"]) / max(float(m["height"]), 1e-3), float(m["top_visible"]),
        float(m["covered"]), float(m["flare"]), float(m["n_members"]),
        math.log(max(float(m["members_volume"]), 1e-7)),
    ]  # fmt: skip
    # log of the mass each material would give this piece (shell or solid, nominal density)
    per_mat = []
    for n in MATERIAL_NAMES:
        mat = MATERIALS[n]
        v = vol if mat.wall is None else min(vol, area * mat.wall)
        per_mat.append(math.log(max(v * mat.density, 1e-4)))
    expected = sum(float(m[f"post_{n}"]) * x for n, x in zip(MATERIAL_NAMES, per_mat, strict=True))
    return np.array([*app, missing, *post, *shape, *top, *sizes, *logs, *geo, *per_mat, expected])


def _softmax(z: np.ndarray) -> np.ndarray:
    z = z - z.max(axis=1, keepdims=True)
    e = np.exp(z)
    return e / e.sum(axis=1, keepdims=True)


def fit_softmax(x: np.ndarray, y: np.ndarray, k: int, l2: float, iters: int = 600) -> np.ndarray:
    """Weights (d + 1, k) of an L2-regularised multinomial logistic regression of labels
    `y` (ints < k) on standardised features `x` (full-batch gradient descent with momentum)."""
    xb = np.hstack([x, np.ones((len(x), 1))])
    w = np.zeros((xb.shape[1], k))
    v = np.zeros_like(w)
    onehot = np.eye(k)[y]
    reg = np.ones((xb.shape[1], 1))
    reg[-1] = 0.0  # no penalty on the bias
    lr = 0.5
    for _ in range(iters):
        grad = xb.T @ (_softmax(xb @ w) - onehot) / len(x) + l2 * reg * w
        v = 0.9 * v - lr * grad
        w = w + v
    return w


def fit_ridge(x: np.ndarray, y: np.ndarray, l2: float) -> np.ndarray:
    """Weights (d + 1,) of a ridge regression of `y` on standardised features `x`."""
    xb = np.hstack([x, np.ones((len(x), 1))])
    reg = l2 * len(x) * np.eye(xb.shape[1])
    reg[-1, -1] = 0.0
    return np.linalg.solve(xb.T @ xb + reg, xb.T @ y)


def best_temperature(logits: np.ndarray, y: np.ndarray) -> float:
    """The temperature that minimises the held-out negative log-likelihood of `y`."""
    grid = np.exp(np.linspace(math.log(0.3), math.log(5.0), 40))
    nll = [-np.mean(np.log(_softmax(logits / t)[np.arange(len(y)), y] + 1e-12)) for t in grid]
    return float(grid[int(np.argmin(nll))])


@dataclass(frozen=True)
class Prediction:
    """The model's reading of one object."""

    material: dict[str, float]  # posterior over materials
    mass_class: np.ndarray  # P(class) at `MASS_BOUNDS`
    mass: float  # kg, inside the most likely class


@dataclass(frozen=True)
class AttributeModel:
    """The three heads (module docstring) over standardised `features`."""

    mean: np.ndarray
    std: np.ndarray
    w_material: np.ndarray
    w_mass_class: np.ndarray
    w_mass: np.ndarray
    t_material: float = 1.0
    t_mass_class: float = 1.0
    #: "learned": mass from the two mass heads; "rule": the hand-built volume x density
    #: rule (`material.estimate_mass`) on the learned material (chosen by cross-validation)
    mass_head: str = "learned"
    #: the appearance-only material head over the first `N_APPEARANCE` columns (None: none)
    w_appearance: np.ndarray | None = None
    #: weight of the all-feature material head's logits (1 - pool: the appearance head's)
    pool: float = 1.0
    #: weight of the hand-built mixture's log posterior added to the pooled logits
    handbuilt: float = 0.0

    def _xb(self, x: np.ndarray) -> np.ndarray:
        z = (np.atleast_2d(x) - self.mean) / self.std
        return np.hstack([z, np.ones((len(z), 1))])

    def material_experts(
        self, x: np.ndarray, xb: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """The material experts' logits of feature rows `x`: the all-feature head's, the
        appearance head's (None without one) and the hand-built log posterior (`xb`: the
        rows standardised, if already computed)."""
        x = np.atleast_2d(x)
        xb = self._xb(x) if xb is None else xb
        appearance = None
        if self.w_appearance is not None:
            appearance = np.hstack([xb[:, :N_APPEARANCE], xb[:, -1:]]) @ self.w_appearance
        return xb @ self.w_material, appearance, x[:, POSTERIOR]

    def material_logits(self, x: np.ndarray, xb: np.ndarray | None = None) -> np.ndarray:
        """The pooled material logits (before the temperature) of feature rows `x`."""
        logits, appearance, posterior = self.material_experts(x, xb)
        if appearance is not None and self.pool < 1.0:
            logits = self.pool * logits + (1.0 - self.pool) * appearance
        return logits + self.handbuilt * posterior

    def predict(self, m: Mapping[str, float | str]) -> Prediction:
        """The attributes of an object from its measurements (`measurements`)."""
        x = features(m)
        xb = self._xb(x)
        pm = _softmax(self.material_logits(x, xb) / self.t_material)[0]
        pc = _softmax(xb @ self.w_mass_class / self.t_mass_class)[0]
        c = int(np.argmax(pc))
        lo = MASS_BOUNDS[c - 1] if c > 0 else 0.0
        hi = MASS_BOUNDS[c] if c < len(MASS_BOUNDS) else math.inf
        mass = float(np.exp(xb @ self.w_mass)[0])
        # inside the class, clear of its bounds (the rules compare with <= / <)
        mass = min(max(mass, lo * 1.02 if lo else 0.02), hi * 0.98)
        post = {n: float(p) for n, p in zip(MATERIAL_NAMES, pm, strict=True)}
        return Prediction(post, pc, mass)

    def to_json(self) -> dict[str, object]:
        r = 6
        return {
            "materials": list(MATERIAL_NAMES), "mass_bounds": list(MASS_BOUNDS),
            "mean": np.round(self.mean, r).tolist(), "std": np.round(self.std, r).tolist(),
            "w_material": np.round(self.w_material, r).tolist(),
            "w_mass_class": np.round(self.w_mass_class, r).tolist(),
            "w_mass": np.round(self.w_mass, r).tolist(),
            "t_material": self.t_material, "t_mass_class": self.t_mass_class,
            "mass_head": self.mass_head, "pool": self.pool, "handbuilt": self.handbuilt,
            **({} if self.w_appearance is None else
               {"w_appearance": np.round(self.w_appearance, r).tolist()}),
        }  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping[str, object], source: str = "model") -> AttributeModel:
        if tuple(data["materials"]) != MATERIAL_NAMES:  # type: ignore[arg-type]
            raise AssetError(f"{source}: materials {data['materials']} != {list(MATERIAL_NAMES)}")
        if tuple(data["mass_bounds"]) != MASS_BOUNDS:  # type: ignore[arg-type]
            raise AssetError(f"{source}: mass_bounds {data['mass_bounds']} != {list(MASS_BOUNDS)}")
        arr = {k: np.asarray(data[k], dtype=float) for k in
               ("mean", "std", "w_material", "w_mass_class", "w_mass")}  # fmt: skip
        head = str(data.get("mass_head", "learned"))
        if head not in ("learned", "rule"):
            raise AssetError(f"{source}: mass_head {head!r} is neither 'learned' nor 'rule'")
        pool = float(data.get("pool", 1.0))  # type: ignore[arg-type]
        if not 0.0 <= pool <= 1.0:
            raise AssetError(f"{source}: pool {pool} is not within [0, 1]")
        w_app = data.get("w_appearance")
        if w_app is not None:
            w_app = np.asarray(w_app, dtype=float)
            want = (N_APPEARANCE + 1, len(MATERIAL_NAMES))
            if w_app.shape != want:
                raise AssetError(f"{source}: w_appearance has shape {w_app.shape}, not {want}")
        elif pool < 1.0:
            raise AssetError(f"{source}: pool {pool} < 1 needs w_appearance")
        handbuilt = float(data.get("handbuilt", 0.0))  # type: ignore[arg-type]
        if handbuilt < 0.0:
            raise AssetError(f"{source}: handbuilt {handbuilt} is negative")
        return cls(
            **arr,
            t_material=float(data["t_material"]),  # type: ignore[arg-type]
            t_mass_class=float(data["t_mass_class"]),  # type: ignore[arg-type]
            mass_head=head,
            w_appearance=w_app,
            pool=pool,
            handbuilt=handbuilt,
        )


def learned_confidences(
    pred: Prediction, chosen: str, covered: float
) -> tuple[dict[str, float], dict[str, tuple]]:
    """(confidence, alternatives) of one object read by the model, in the form of
    `confidence.raw_confidences` (material and robustness from its material posterior, mass
    from its class posterior: the alternatives the heaviest mass of each other plausible
    class; members from the geometry)."""
    conf: dict[str, float] = {}
    alts: dict[str, tuple] = {}
    ranked = sorted(pred.material.items(), key=lambda kv: -kv[1])
    conf["material"] = float(pred.material[chosen])
    alts["material"] = tuple(m for m, p in ranked if m != chosen and p >= ALT_MIN)
    rob: dict[str, float] = {}
    for m, p in pred.material.items():
        rob[MATERIALS[m].robustness] = rob.get(MATERIALS[m].robustness, 0.0) + p
    mine = MATERIALS[chosen].robustness
    conf["robustness"] = float(rob[mine])
    alts["robustness"] = tuple(
        r for r, p in sorted(rob.items(), key=lambda kv: -kv[1]) if r != mine and p >= ALT_MIN
    )
    c = mass_class(pred.mass)
    conf["mass"] = float(pred.mass_class[c])
    order = [k for k in np.argsort(-pred.mass_class, kind="stable")
             if k != c and pred.mass_class[k] >= ALT_MIN]  # fmt: skip
    alts["mass"] = tuple(round(heaviest_in_class(int(k)), 4) for k in order)
    conf["members"] = float(np.clip(1.0 - covered, 0.0, 1.0))
    alts["members"] = ()
    return conf, alts


def heaviest_in_class(c: int) -> float:
    """kg: a mass near the top of class `c` (the last class: half again its lower bound)."""
    return MASS_BOUNDS[c] * 0.98 if c < len(MASS_BOUNDS) else MASS_BOUNDS[-1] * 1.5


@lru_cache(maxsize=1)
def packaged_attribute_model() -> AttributeModel | None:
    """The trained model shipped with the package, or None if there is none."""
    try:
        path = Path(asset_path(*MODEL_FILE))
    except AssetError:
        return None
    return AttributeModel.from_json(json.loads(path.read_text()), str(path))


__all__ = [
    "MODEL_FILE",
    "N_APPEARANCE",
    "POSTERIOR",
    "AttributeModel",
    "Prediction",
    "best_temperature",
    "features",
    "fit_ridge",
    "fit_softmax",
    "heaviest_in_class",
    "learned_confidences",
    "measurements",
    "packaged_attribute_model",
]
