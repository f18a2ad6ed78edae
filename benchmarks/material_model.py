"""Train and measure the material-from-appearance classifier of `utamp2-perceived`.

Renders the suites' scenes with every object's material drawn at random (so that material
and shape are independent: the classifier may only learn appearance), takes the survey
look (`MujocoBackend.survey`), computes each object's appearance features
(`utamp_gym.perception.material.appearance_features`) and fits a Gaussian per material
(plain numpy). It is compared, on held-out scenes, with the nearest palette colour and with
scikit-learn's classifiers when scikit-learn is installed (``pip install scikit-learn``;
not a dependency of the package). Writes the model to
``assets/perception/material_model.json`` (`--write-model`) and the measurement to
``docs/results/material_model.{md,json}``.

    python benchmarks/material_model.py --scenes 240
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from pathlib import Path

import numpy as np

from utamp_gym.perception.material import (
    FEATURES,
    PRIOR_ALPHA,
    MaterialModel,
    appearance_features,
    nearest_palette,
    shape_prior,
)
from utamp_gym.perception.objects import instance_pixels, perceive_objects
from utamp_gym.provenance import commit, write_json, write_markdown
from utamp_gym.resources import asset_path
from utamp_gym.scene.catalogue import load_catalogue
from utamp_gym.scene.materials import MATERIALS
from utamp_gym.seeding import run_seed
from utamp_gym.sim.backend import MujocoBackend
from utamp_gym.suites import suite_scenes

ROOT = Path(__file__).resolve().parents[1]


def samples(n_scenes: int, seed: int) -> tuple[np.ndarray, list[str], list[int]]:
    """Features, material labels and scene index of every object in `n_scenes` renders."""
    rng = np.random.default_rng(seed)
    pool = [*suite_scenes("pick-place"), *suite_scenes("sliding"), *suite_scenes("extra")]
    names = sorted(MATERIALS)
    backend = MujocoBackend()
    xs, ys, groups = [], [], []
    try:
        for k in range(n_scenes):
            scene = pool[int(rng.integers(len(pool)))]
            drawn = {o.name: names[int(rng.integers(len(names)))] for o in scene.objects}
            types = {
                f"{o.name}-as-{drawn[o.name]}": scene.type_of(o.name)._replace(
                    name=f"{o.name}-as-{drawn[o.name]}", material=drawn[o.name]
                )
                for o in scene.objects
            }
            objects = tuple(o._replace(type=f"{o.name}-as-{drawn[o.name]}") for o in scene.objects)
            recoloured = scene._replace(
                catalogue=scene.catalogue.merged(types),
                objects=objects,
                goal_base=scene.tower_base,
            )
            backend.reset(recoloured, np.random.default_rng([seed, k]))
            bundle = backend.survey()
            for i, name in backend.cameras.instances.items():
                pixels = instance_pixels(bundle, i)
                if sum(len(c) for _, c in pixels) < 50:
                    continue
                xs.append(appearance_features(pixels))
                ys.append(drawn[name])
                groups.append(k)
            if (k + 1) % 20 == 0:
                print(f"{k + 1}/{n_scenes} scenes, {len(ys)} objects", flush=True)
    finally:
        backend.close()
    return np.array(xs), ys, groups


def catalogue_types() -> list:
    """The packaged catalogues' types (the material prior is counted over them)."""
    out = []
    for name in ("kitchen.toml", "extra.toml"):
        out.extend(load_catalogue(asset_path("objects", name)).types.values())
    return out


def natural(n_scenes: int) -> list[tuple[np.ndarray, str, str]]:
    """(features, perceived shape class, true material) of the objects of the first
    `n_scenes` of each suite, rendered as the suites declare them (seed 0)."""
    out = []
    backend = MujocoBackend()
    try:
        for suite in ("pick-place", "sliding", "extra"):
            for scene in suite_scenes(suite)[:n_scenes]:
                backend.reset(scene, np.random.default_rng(run_seed(scene.name, 0)))
                bundle = backend.survey()
                names = backend.cameras.instances
                for i, p in perceive_objects(bundle).items():
                    o = scene.object(names[i])
                    pixels = instance_pixels(bundle, i)
                    if sum(len(c) for _, c in pixels) < 50:
                        continue
                    out.append(
                        (
                            appearance_features(pixels),
                            p.shape_class(o.orientation),
                            scene.type_of(o.name).material,
                        )
                    )
    finally:
        backend.close()
    return out


def confusion(truth: list[str], guess: list[str]) -> dict[str, dict[str, int]]:
    out: dict[str, dict[str, int]] = {}
    for t, g in zip(truth, guess, strict=True):
        out.setdefault(t, Counter())[g] += 1  # type: ignore[arg-type]
    return {t: dict(c) for t, c in sorted(out.items())}


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=240)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--write-model", action="store_true")
    ap.add_argument("--cache", type=Path, help="reuse / keep the rendered features in this .npz")
    ap.add_argument(
        "--natural", type=int, default=20, help="scenes per suite for the in-context measure"
    )
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    t0 = time.perf_counter()
    if args.cache is not None and args.cache.is_file():
        data = np.load(args.cache)
        x, y, g = data["x"], [str(v) for v in data["y"]], [int(v) for v in data["g"]]
    else:
        x, y, g = samples(args.scenes, args.seed)
        if args.cache is not None:
            np.savez(args.cache, x=x, y=np.array(y), g=np.array(g))
    render_s = time.perf_counter() - t0
    groups = np.asarray(g)
    test = groups % 4 == 0  # every fourth scene held out
    ytr = [v for v, t in zip(y, test, strict=True) if not t]
    yte = [v for v, t in zip(y, test, strict=True) if t]
    results: dict[str, dict[str, object]] = {}

    def record(name: str, guess: list[str], fit_s: float, predict_s: float) -> None:
        acc = float(np.mean([a == b for a, b in zip(guess, yte, strict=True)]))
        results[name] = {
            "accuracy": round(acc, 4),
            "fit_ms": round(1000 * fit_s, 1),
            "predict_us_per_object": round(1e6 * predict_s / max(1, len(yte)), 1),
            "confusion": confusion(yte, guess),
        }

    t = time.perf_counter()
    model = MaterialModel.fit(x[~test], ytr)
    fit_s = time.perf_counter() - t
    model = model.calibrated(x[test], yte)  # the temperature only: accuracy is unchanged
    t = time.perf_counter()
    guess = [model.classify(v).name for v in x[test]]
    record("gaussian (numpy, this package)", guess, fit_s, time.perf_counter() - t)
    t = time.perf_counter()
    guess = [nearest_palette(v).name for v in x[test]]
    record("nearest palette colour (numpy)", guess, 0.0, time.perf_counter() - t)
    try:
        from sklearn.ensemble import RandomForestClassifier
        from sklearn.neighbors import KNeighborsClassifier
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler
        from sklearn.svm import SVC
    except ImportError:
        print("scikit-learn not installed: its classifiers are not measured")
        forest = None
    else:
        for name, clf in (
            ("random forest (scikit-learn)", RandomForestClassifier(300, random_state=0)),
            (
                "k nearest neighbours, k=7 (scikit-learn)",
                make_pipeline(StandardScaler(), KNeighborsClassifier(7)),
            ),
            ("RBF SVM (scikit-learn)", make_pipeline(StandardScaler(), SVC())),
        ):
            t = time.perf_counter()
            clf.fit(x[~test], ytr)
            fit_s = time.perf_counter() - t
            t = time.perf_counter()
            guess = [str(v) for v in clf.predict(x[test])]
            record(name, guess, fit_s, time.perf_counter() - t)
        forest = RandomForestClassifier(300, random_state=0).fit(x[~test], ytr)
    # in context: the suites' own objects, perceived shape class, with and without the prior
    prior = shape_prior(catalogue_types())
    contextual = model.with_prior(prior)
    nat = natural(args.natural)
    in_context = {
        "appearance only": float(np.mean([model.classify(x).name == m for x, _, m in nat])),
        "appearance x shape prior": float(
            np.mean([contextual.classify(x, c).name == m for x, c, m in nat])
        ),
    }
    if forest is not None:  # scikit-learn's random forest, with the same prior
        names = list(forest.classes_)

        def forest_in_context(x: np.ndarray, shape: str) -> str:
            proba = forest.predict_proba(x[None, :])[0]
            ctx = prior.get(shape, {})
            scores = [p * ctx.get(n, 1.0) for p, n in zip(proba, names, strict=True)]
            return str(names[int(np.argmax(scores))])

        in_context["random forest (scikit-learn) only"] = float(
            np.mean([str(forest.predict(x[None, :])[0]) == m for x, _, m in nat])
        )
        in_context["random forest (scikit-learn) x shape prior"] = float(
            np.mean([forest_in_context(x, c) == m for x, c, m in nat])
        )
    nat_conf = confusion(
        [m for _, _, m in nat], [contextual.classify(x, c).name for x, c, _ in nat]
    )
    args.out.mkdir(parents=True, exist_ok=True)
    summary = {
        "scenes": args.scenes,
        "objects": len(y),
        "train_objects": len(ytr),
        "test_objects": len(yte),
        "features": list(FEATURES),
        "render_and_features_s": round(render_s, 1),
        "classifiers": results,
        "temperature": model.temperature,
        "prior_alpha": PRIOR_ALPHA,
        "in_context_objects": len(nat),
        "in_context_accuracy": {k: round(v, 4) for k, v in in_context.items()},
        "in_context_confusion": nat_conf,
    }
    prov = write_json(args.out / "material_model.json", summary, indent=2)
    lines = [
        f"Material from appearance: {len(yte)} held-out objects (every fourth of "
        f"{args.scenes} rendered scenes; {len(ytr)} objects to train), materials drawn at "
        "random per object (`benchmarks/material_model.py`).",
        "",
        "| classifier | accuracy | fit (ms) | predict (us / object) |",
        "|---|---|---|---|",
    ]
    for name, r in results.items():
        lines.append(
            f"| {name} | {r['accuracy']:.3f} | {r['fit_ms']} | {r['predict_us_per_object']} |"
        )
    best = results["gaussian (numpy, this package)"]["confusion"]
    lines += ["", "Confusions of the packaged classifier (true material: guesses):", ""]
    for t, c in best.items():  # type: ignore[union-attr]
        lines.append(
            f"* {t}: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items(), key=lambda kv: -kv[1]))
        )
    lines += [
        "",
        f"On the suites' own objects ({len(nat)} objects of the first {args.natural} scenes of "
        "pick-place, sliding and extra, as declared, seed 0), where shape and material go "
        "together: "
        + "; ".join(f"{k} {v:.3f}" for k, v in in_context.items())
        + ". Confusions of the packaged classifier there (true: guesses):",
        "",
    ]
    for t, c in nat_conf.items():
        lines.append(
            f"* {t}: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items(), key=lambda kv: -kv[1]))
        )
    write_markdown(args.out / "material_model.md", "\n".join(lines) + "\n", prov)
    print("\n".join(lines))
    if args.write_model:
        full = MaterialModel.fit(x, y).with_prior(prior, model.temperature)
        path = ROOT / "assets" / "perception" / "material_model.json"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(full.to_json(), indent=1) + "\n")
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
