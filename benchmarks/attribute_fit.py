"""The fitting and the held-out sets of `attribute_model.py` (train): the model fitted on rows
of the perceiver's measurements, leave-one-family-out folds, and the choice of the material
experts' pooling on held-out objects (`choose_material`)."""

from __future__ import annotations

import numpy as np

from utamp_gym.perception.confidence import mass_class
from utamp_gym.perception.learned import (
    MATERIAL_NAMES,
    N_APPEARANCE,
    AttributeModel,
    best_temperature,
    features,
    fit_ridge,
    fit_softmax,
)
from utamp_gym.suites import suite_scenes
from utamp_gym.tasks.attributes import family_of

TRAIN = "procedural-v1/train"
POOL_GRID = (0.0, 0.1, 0.25, 0.4, 0.5, 0.75, 1.0)  # weight of the all-feature material head
HANDBUILT_GRID = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0)  # weight of the hand-built log posterior


def arrays(rows: list[dict[str, object]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(features, material index, mass class, log mass) of `rows`."""
    x = np.array([features(r["measurements"]) for r in rows])  # type: ignore[arg-type]
    mat = np.array([MATERIAL_NAMES.index(r["declared"]["material"]) for r in rows])  # type: ignore[index]
    kg = np.array([float(r["declared"]["mass"]) for r in rows])  # type: ignore[index]
    return x, mat, np.array([mass_class(m) for m in kg]), np.log(kg)


def fit(
    rows: list[dict[str, object]],
    l2: tuple[float, float, float],
    temps: tuple[float, float] = (1.0, 1.0),
    mass_head: str = "learned",
    pool: float = 1.0,
    handbuilt: float = 0.0,
) -> AttributeModel:
    """The model fitted on `rows` with regularisation `l2` (material, class, mass); `pool`
    < 1 fits the appearance-only material head too (`learned.AttributeModel.pool`)."""
    x, mat, cls, logm = arrays(rows)
    mean, std = x.mean(axis=0), x.std(axis=0)
    std = np.where(std < 1e-9, 1.0, std)
    z = (x - mean) / std
    appearance = None
    if pool < 1.0:
        appearance = fit_softmax(z[:, :N_APPEARANCE], mat, len(MATERIAL_NAMES), l2[0])
    return AttributeModel(
        mean, std,
        fit_softmax(z, mat, len(MATERIAL_NAMES), l2[0]),
        fit_softmax(z, cls, 5, l2[1]),
        fit_ridge(z, logm, l2[2]),
        *temps, mass_head, appearance, pool, handbuilt,
    )  # fmt: skip


def logits(model: AttributeModel, rows: list[dict[str, object]]) -> tuple[np.ndarray, np.ndarray]:
    x = np.array([features(r["measurements"]) for r in rows])  # type: ignore[arg-type]
    return model.material_logits(x), model._xb(x) @ model.w_mass_class


def index(r: dict[str, object]) -> int:
    return int(str(r["scene"]).rsplit("/", 1)[-1])


def families(rows: list[dict[str, object]]) -> list[str]:
    """The kitchenware family of each row's object ("" for the paper's objects)."""
    wanted = {str(r["scene"]) for r in rows if str(r["scene"]).startswith(TRAIN)}
    types = {
        (scene.name, o): scene.object(o).type
        for scene in suite_scenes(TRAIN) if scene.name in wanted
        for o in scene.object_names
    }  # fmt: skip
    return [
        family_of(types[(str(r["scene"]), str(r["object"]))])
        if str(r["scene"]).startswith(TRAIN) else ""
        for r in rows
    ]  # fmt: skip


Folds = list[tuple[list[dict[str, object]], list[dict[str, object]]]]


def family_folds(rows: list[dict[str, object]], fams: list[str]) -> Folds:
    """Leave-one-family-out: per family of `fams` (one per row, `families`; "" is never
    held out), (every other row, that family's rows)."""
    return [
        ([r for r, f in zip(rows, fams, strict=True) if f != name],
         [r for r, f in zip(rows, fams, strict=True) if f == name])
        for name in sorted(set(fams) - {""})
    ]  # fmt: skip


def choose_material(
    fold_sets: tuple[Folds, ...], l2: tuple[float, float, float]
) -> tuple[float, float, float, dict[str, float]]:
    """(pool, handbuilt, temperature, mean held-out accuracy per "pool/handbuilt"): the
    pooling of the material experts (`learned.AttributeModel`) whose material reads the
    held-out rows best, on average over the fold sets (each set: its held-out rows pooled;
    ties go to the larger pool and the smaller hand-built weight), and the temperature
    that gives its confidences the least negative log-likelihood over all of them."""
    held = []
    for folds in fold_sets:
        full, app, post, ys = [], [], [], []
        for a, b in folds:
            x, mat, _, _ = arrays(b)
            f, ap, p = fit(a, l2, pool=0.0).material_experts(x)
            full.append(f)
            app.append(ap)
            post.append(p)
            ys.append(mat)
        held.append((np.vstack(full), np.vstack(app), np.vstack(post), np.concatenate(ys)))
    accuracy: dict[tuple[float, float], float] = {}
    for w in POOL_GRID:
        for h in HANDBUILT_GRID:
            right = [np.mean(np.argmax(w * f + (1.0 - w) * a + h * p, 1) == y)
                     for f, a, p, y in held]  # fmt: skip
            accuracy[(w, h)] = round(float(np.mean(right)), 4)
    w, h = min(accuracy, key=lambda k: (-accuracy[k], -k[0], k[1]))
    pooled = np.vstack([w * f + (1.0 - w) * a + h * p for f, a, p, _ in held])
    t = best_temperature(pooled, np.concatenate([y for *_, y in held]))
    return w, h, t, {f"{a}/{b}": v for (a, b), v in accuracy.items()}


__all__ = [
    "HANDBUILT_GRID",
    "POOL_GRID",
    "TRAIN",
    "Folds",
    "arrays",
    "choose_material",
    "families",
    "family_folds",
    "fit",
    "index",
    "logits",
]
