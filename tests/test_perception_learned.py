"""The learned attribute model (perception/learned.py): its fitting, its shipped weights, and
the confidences it gives in the form the planner under doubt reads."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from measurements import cylinder_measurements

from utamp_gym.errors import AssetError
from utamp_gym.perception.confidence import MASS_BOUNDS, mass_class
from utamp_gym.perception.learned import (
    MATERIAL_NAMES,
    MODEL_FILE,
    N_APPEARANCE,
    AttributeModel,
    Prediction,
    best_temperature,
    features,
    fit_ridge,
    fit_softmax,
    learned_confidences,
    packaged_attribute_model,
)
from utamp_gym.resources import asset_path


def test_softmax_regression_separates_and_ridge_recovers_a_line() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(300, 2))
    y = np.digitize(x[:, 0] + x[:, 1], [-0.7, 0.7])  # three classes, linearly separable
    w = fit_softmax(x, y, 3, l2=1e-4)
    pred = np.argmax(np.hstack([x, np.ones((300, 1))]) @ w, axis=1)
    assert np.mean(pred == y) > 0.9
    t = 2.0 * x[:, 0] - x[:, 1] + 0.5
    assert np.allclose(fit_ridge(x, t, 0.0), [2.0, -1.0, 0.5], atol=1e-6)


def test_temperature_softens_an_overconfident_model() -> None:
    rng = np.random.default_rng(1)
    y = rng.integers(0, 2, size=400)
    logits = np.zeros((400, 2))
    logits[np.arange(400), y] = 8.0  # sure of the label ...
    flip = rng.random(400) < 0.3  # ... and wrong on 30 %
    logits[flip] = logits[flip][:, ::-1]
    assert best_temperature(logits, y) > 3.0


def test_the_shipped_model_round_trips_and_rejects_other_materials() -> None:
    model = packaged_attribute_model()
    assert model is not None, "assets/perception/attribute_model.json is shipped"
    again = AttributeModel.from_json(json.loads(json.dumps(model.to_json())))
    assert np.allclose(again.w_material, model.w_material)
    assert (
        again.mass_head
        == model.mass_head
        == json.loads((Path(asset_path(*MODEL_FILE))).read_text())["mass_head"]
    )
    with pytest.raises(AssetError, match="mass_head 'guess'"):
        AttributeModel.from_json({**model.to_json(), "mass_head": "guess"}, "x.json")
    bad = {**model.to_json(), "materials": ["wood"]}
    with pytest.raises(AssetError, match="materials"):
        AttributeModel.from_json(bad, "x.json")


def test_learned_confidences_name_the_other_classes_and_robustness() -> None:
    post = dict.fromkeys(MATERIAL_NAMES, 0.0) | {"ceramic": 0.6, "plastic": 0.4}
    pred = Prediction(post, np.array([0.0, 0.7, 0.3, 0.0, 0.0]), 0.8)
    conf, alts = learned_confidences(pred, "ceramic", covered=0.25)
    assert conf["material"] == 0.6 and alts["material"] == ("plastic",)
    assert conf["robustness"] == 0.6 and alts["robustness"] == ("sturdy",)  # plastic
    assert conf["mass"] == 0.7 and mass_class(alts["mass"][0]) == 2  # 1.1-1.5 kg
    assert alts["mass"][0] < MASS_BOUNDS[2] and conf["members"] == 0.75


def _blank_model(**kw: object) -> AttributeModel:
    """A model whose fitted heads know nothing (all weights zero)."""
    d = len(features(_measurements()))
    k = len(MATERIAL_NAMES)
    return AttributeModel(
        np.zeros(d),
        np.ones(d),
        np.zeros((d + 1, k)),
        np.zeros((d + 1, 5)),
        np.zeros(d + 1),
        **kw,  # type: ignore[arg-type]
    )


def _measurements() -> dict[str, float | str]:
    post = {n: 0.01 for n in MATERIAL_NAMES} | {"ceramic": 0.7, "glass": 0.2}
    return cylinder_measurements(posterior=post)


def test_the_handbuilt_expert_carries_its_posterior_into_the_pooled_material() -> None:
    m = _measurements()
    alone = _blank_model().predict(m).material  # no expert with an opinion: uniform
    assert max(alone.values()) == pytest.approx(1.0 / len(MATERIAL_NAMES))
    post = _blank_model(handbuilt=1.0).predict(m).material  # log posterior, temperature 1
    total = sum(float(m[f"post_{n}"]) for n in MATERIAL_NAMES)
    assert post["ceramic"] == pytest.approx(0.7 / total)
    assert post["glass"] == pytest.approx(0.2 / total)
    sharper = _blank_model(handbuilt=2.0).predict(m).material
    assert sharper["ceramic"] > post["ceramic"]
    # the appearance head's logits count with weight 1 - pool
    w_app = np.zeros((N_APPEARANCE + 1, len(MATERIAL_NAMES)))
    w_app[-1, MATERIAL_NAMES.index("wood")] = 4.0  # its bias: wood
    for pool, wood in ((1.0, False), (0.0, True)):
        p = _blank_model(w_appearance=w_app, pool=pool).predict(m).material
        assert (max(p, key=p.__getitem__) == "wood") is wood


def test_the_pooled_model_round_trips_and_rejects_an_inconsistent_pooling() -> None:
    w_app = np.arange((N_APPEARANCE + 1) * len(MATERIAL_NAMES), dtype=float).reshape(
        N_APPEARANCE + 1, -1
    )
    model = _blank_model(w_appearance=w_app, pool=0.4, handbuilt=2.0)
    again = AttributeModel.from_json(json.loads(json.dumps(model.to_json())))
    assert again.pool == 0.4 and again.handbuilt == 2.0
    assert np.array_equal(again.w_appearance, w_app)  # type: ignore[arg-type]
    data = model.to_json()
    for change, message in (
        ({"pool": 1.5}, "pool 1.5 is not within"),
        ({"handbuilt": -1.0}, "handbuilt -1.0 is negative"),
        ({"w_appearance": w_app[:-1].tolist()}, "w_appearance has shape"),
    ):
        with pytest.raises(AssetError, match=message):
            AttributeModel.from_json({**data, **change}, "x.json")
    no_app = {k: v for k, v in data.items() if k != "w_appearance"}
    with pytest.raises(AssetError, match="needs w_appearance"):
        AttributeModel.from_json(no_app, "x.json")
    old = {k: v for k, v in no_app.items() if k not in ("pool", "handbuilt")}
    assert AttributeModel.from_json(old).pool == 1.0  # a file from before the pooling
