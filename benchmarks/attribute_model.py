"""Train the learned attribute model (`utamp_gym.perception.learned`) on procedural-v1/train.

``collect``: each scene of ``--suite`` is reset with its episode seed (seed 0, as `utamp
eval` does), surveyed, and every object fitted; its measurements (`learned.measurements`:
appearance, the hand-built material posterior, shape and geometry) and its declared
material, mass and robustness are cached per scene under ``--cache/<suite>`` (resumable;
``--part I/N`` collects every N-th scene, for parallel processes).

``train``: development data only — the train split's measurements. Even-numbered scenes
fit, odd-numbered ones are held out to choose the regularisation and the temperatures (and
vice versa for the reported cross-validated accuracy); the shipped model is refitted on all
train objects with the chosen settings and written to
``assets/perception/attribute_model.json`` (``--write``).

``report``: the shipped model on the measurements of the ``--suite`` split(s) (test splits:
reported only, never used to choose anything): per-attribute accuracy, the hand-built
pipeline's beside it, and a reliability table of the confidences; writes
``docs/results/attribute-model.{md,json}``.

    python benchmarks/attribute_model.py collect [--suite procedural-v1/train] [--part 1/2]
    python benchmarks/attribute_model.py train [--write]
    python benchmarks/attribute_model.py report --suite procedural-v1/test-instances,...
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from utamp_gym.backend import DEFAULT_BACKEND, backend_factory
from utamp_gym.perception.confidence import mass_class
from utamp_gym.perception.learned import (
    MATERIAL_NAMES,
    MODEL_FILE,
    AttributeModel,
    best_temperature,
    features,
    fit_ridge,
    fit_softmax,
    measurements,
)
from utamp_gym.perception.material import appearance_features, classify_material
from utamp_gym.perception.objects import (
    _shell_area,
    _solid_volume,
    instance_pixels,
    perceive_objects,
)
from utamp_gym.seeding import run_seed
from utamp_gym.suites import suite_scenes

ROOT = Path(__file__).resolve().parents[1]
TRAIN = "procedural-v1/train"
L2_GRID = (1e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1)


def scene_rows(scene, sim) -> list[dict[str, object]]:  # type: ignore[no-untyped-def]
    """One row per object of `scene`: its measurements and its declared attributes."""
    sim.reset(scene, np.random.default_rng(run_seed(scene.name, 0)))
    bundle = sim.survey()
    names = sim.cameras.instances
    rows = []
    for i, p in perceive_objects(bundle).items():
        name = names[i]
        declared = scene.type_of(name)
        colours = instance_pixels(bundle, i)
        cls = p.shape_class()
        gmm = classify_material(colours, cls)  # the hand-built pipeline's reading
        m = measurements(
            p.shape, appearance_features(colours), gmm.posterior, cls,
            _solid_volume(p.shape), _shell_area(p.shape),
        )  # fmt: skip
        rows.append({
            "scene": scene.name, "object": name, "n_objects": scene.n_objects,
            "measurements": m, "handbuilt": {"material": gmm.name, "mass": p.mass},
            "declared": {"material": declared.material, "mass": declared.mass,
                         "robustness": declared.robustness},
        })  # fmt: skip
    return rows


def collect(suite: str, cache: Path, part: tuple[int, int] = (1, 1)) -> list[dict[str, object]]:
    """The rows of every scene of `suite` (rendered once, then read from `cache`)."""
    folder = cache / suite.replace("/", "_")
    folder.mkdir(parents=True, exist_ok=True)
    i, n = part
    sim = None
    out: list[dict[str, object]] = []
    for k, scene in enumerate(suite_scenes(suite)):
        if k % n != i - 1:
            continue
        path = folder / (scene.name.rsplit("/", 1)[-1] + ".json")
        if not path.exists():
            sim = sim or backend_factory(DEFAULT_BACKEND)()
            path.write_text(json.dumps(scene_rows(scene, sim)))
        out += json.loads(path.read_text())
    if sim is not None:
        sim.close()
    return out


def cached(suite: str, cache: Path) -> list[dict[str, object]]:
    folder = cache / suite.replace("/", "_")
    return [r for p in sorted(folder.glob("*.json")) for r in json.loads(p.read_text())]


def arrays(rows: list[dict[str, object]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(features, material index, mass class, log mass) of `rows`."""
    x = np.array([features(r["measurements"]) for r in rows])  # type: ignore[arg-type]
    mat = np.array([MATERIAL_NAMES.index(r["declared"]["material"]) for r in rows])  # type: ignore[index]
    kg = np.array([float(r["declared"]["mass"]) for r in rows])  # type: ignore[index]
    return x, mat, np.array([mass_class(m) for m in kg]), np.log(kg)


def fit(rows: list[dict[str, object]], l2: tuple[float, float, float],
        temps: tuple[float, float] = (1.0, 1.0)) -> AttributeModel:  # fmt: skip
    """The model fitted on `rows` with regularisation `l2` (material, class, mass)."""
    x, mat, cls, logm = arrays(rows)
    mean, std = x.mean(axis=0), x.std(axis=0)
    std = np.where(std < 1e-9, 1.0, std)
    z = (x - mean) / std
    return AttributeModel(
        mean, std,
        fit_softmax(z, mat, len(MATERIAL_NAMES), l2[0]),
        fit_softmax(z, cls, 5, l2[1]),
        fit_ridge(z, logm, l2[2]),
        *temps,
    )  # fmt: skip


def evaluate(model: AttributeModel, rows: list[dict[str, object]]) -> dict[str, object]:
    """Accuracy (material, robustness, mass class) and per-object confidences of `model`."""
    from utamp_gym.scene.materials import material

    out: dict[str, list] = {k: [] for k in ("material", "robustness", "mass")}
    conf: dict[str, list] = {k: [] for k in out}
    for r in rows:
        p = model.predict(r["measurements"])  # type: ignore[arg-type]
        d = r["declared"]  # type: ignore[index]
        name = max(p.material, key=p.material.__getitem__)
        rob = material(name).robustness
        out["material"].append(name == d["material"])
        out["robustness"].append(rob == d["robustness"])
        out["mass"].append(mass_class(p.mass) == mass_class(float(d["mass"])))
        conf["material"].append(p.material[name])
        conf["robustness"].append(
            sum(v for k, v in p.material.items() if material(k).robustness == rob)
        )
        conf["mass"].append(float(p.mass_class[mass_class(p.mass)]))
    return {"right": out, "confidence": conf}


def logits(model: AttributeModel, rows: list[dict[str, object]]) -> tuple[np.ndarray, np.ndarray]:
    x = np.array([features(r["measurements"]) for r in rows])  # type: ignore[arg-type]
    xb = model._xb(x)
    return xb @ model.w_material, xb @ model.w_mass_class


def _index(r: dict[str, object]) -> int:
    return int(str(r["scene"]).rsplit("/", 1)[-1])


def train(cache: Path, write: bool) -> dict[str, object]:
    """Choose settings by even/odd cross-validation on train; fit on all; maybe ship."""
    rows = cached(TRAIN, cache)
    folds = ([r for r in rows if _index(r) % 2 == 0], [r for r in rows if _index(r) % 2 == 1])
    best: list[float] = []
    for head in range(3):
        scores = []
        for l2 in L2_GRID:
            s = []
            for a, b in (folds, folds[::-1]):
                m = fit(a, (l2, l2, l2))
                x, mat, cls, logm = arrays(b)
                xb = m._xb(x)
                if head == 0:
                    s.append(np.mean(np.argmax(xb @ m.w_material, 1) == mat))
                elif head == 1:
                    s.append(np.mean(np.argmax(xb @ m.w_mass_class, 1) == cls))
                else:
                    s.append(-np.mean((xb @ m.w_mass - logm) ** 2))
            scores.append(float(np.mean(s)))
        best.append(L2_GRID[int(np.argmax(scores))])
        print(f"head {head}: l2 grid scores {dict(zip(L2_GRID, np.round(scores, 4), strict=True))}")
    l2 = (best[0], best[1], best[2])
    # temperatures on held-out halves, then the cross-validated accuracy with them
    tm, tc = [], []
    for a, b in (folds, folds[::-1]):
        m = fit(a, l2)
        lm, lc = logits(m, b)
        _, mat, cls, _ = arrays(b)
        tm.append(best_temperature(lm, mat))
        tc.append(best_temperature(lc, cls))
    temps = (float(np.mean(tm)), float(np.mean(tc)))
    held: list[dict[str, object]] = []
    for a, b in (folds, folds[::-1]):
        ev = evaluate(fit(a, l2, temps), b)
        held.append(ev)
    cv_acc = {k: float(np.mean(held[0]["right"][k] + held[1]["right"][k]))  # type: ignore[index,operator]
              for k in ("material", "robustness", "mass")}  # fmt: skip
    model = fit(rows, l2, temps)
    if write:
        path = ROOT / "assets" / Path(*MODEL_FILE)
        path.write_text(json.dumps(model.to_json(), separators=(",", ":")) + "\n")
    return {"l2": l2, "temperatures": temps, "cv_accuracy": cv_acc, "objects": len(rows),
            "cv": held}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("command", choices=("collect", "train", "report"))
    ap.add_argument("--suite", default=TRAIN, help="comma-separated suites")
    ap.add_argument("--part", default="1/1", help="I/N: every N-th scene from the I-th")
    ap.add_argument("--cache", type=Path, default=Path("runs/attribute_model"))
    ap.add_argument("--write", action="store_true", help="ship the trained model")
    args = ap.parse_args()
    if args.command == "collect":
        i, n = (int(v) for v in args.part.split("/"))
        for suite in args.suite.split(","):
            print(suite, len(collect(suite, args.cache, (i, n))), "objects")
    elif args.command == "train":
        out = train(args.cache, args.write)
        print({k: v for k, v in out.items() if k != "cv"})


if __name__ == "__main__":
    main()
