"""The perceiver on procedural-v1/train scenes: diagnosis, confidence calibration and its
reliability table (docs/results/perceiver-train.{md,json}).

Development data only: the test splits are never read here. Each train scene is reset
with its episode seed (seed 0, as `utamp eval` does), surveyed, and every object perceived
(`perception.objects.perceive_objects`); its perceived type is compared with the declared
one (`methods.perceived.attribute_accuracy`; mass judged as its class at the rules'
thresholds, `perception.confidence.MASS_BOUNDS`). Rows are cached per scene under
``--cache`` (resumable). The raw confidences (`perception.confidence.raw_confidences`) of
the even-numbered scenes fit the isotonic calibration written to
``assets/perception/confidence_calibration.json`` (``--write-calibration``); the
reliability table is measured on the odd-numbered ones (held out from the fit); a map is
shipped only for an attribute whose held-out calibration error it lowers.

    python benchmarks/perceiver_train.py [--limit N] [--write-calibration]
        [--cache runs/perceiver_train] [--results docs/results]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
from perceiver_data import cached_rows, reliability_table  # benchmarks/ is on sys.path

from utamp_gym.methods.perceived import align_members, attribute_accuracy
from utamp_gym.perception.confidence import (
    CALIBRATION_FILE,
    SIZE_COVERAGE,
    SURFACE_COVERAGE,
    Calibration,
    mass_class,
    packaged_calibration,
    raw_confidences,
)
from utamp_gym.perception.objects import perceive_objects
from utamp_gym.perception.volumes import mass_areas, solid_volume
from utamp_gym.provenance import commit, write_json, write_markdown
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.seeding import run_seed

ROOT = Path(__file__).resolve().parents[1]
SUITE = "procedural-v1/train"
CALIBRATED = ("material", "robustness", "mass", "members")


def scene_rows(scene, sim) -> list[dict[str, object]]:  # type: ignore[no-untyped-def]
    """One row per object of `scene`: declared and perceived values, raw confidences."""
    sim.reset(scene, np.random.default_rng(run_seed(scene.name, 0)))
    names = sim.cameras.instances
    rows = []
    for i, p in perceive_objects(sim.survey()).items():
        name = names[i]
        obj = scene.object(name)
        declared = scene.type_of(name)
        seen = p.as_type(name, obj.orientation)
        acc = attribute_accuracy(seen, declared, align_members(seen, declared))
        raw, alts = raw_confidences(  # as `perceive_instance` reckons them (a slab solid)
            p.material.posterior, p.material.name, p.mass, solid_volume(p.shape),
            mass_areas(p.shape)[1], p.shape.covered,
        )  # fmt: skip
        right = {
            "material": acc["material"] == 1.0,
            "robustness": acc["robustness"] == 1.0,
            "mass": mass_class(seen.mass) == mass_class(declared.mass),
            "members": acc["members"] == 1.0,
            "member_size": acc["member_size"] == 1.0,
        }
        rows.append({
            "scene": scene.name, "object": name, "n_objects": scene.n_objects,
            "declared": {"material": declared.material, "mass": declared.mass,
                         "members": len(declared.members) - 1},
            "perceived": {"material": seen.material, "mass": seen.mass,
                          "members": len(seen.members) - 1},
            "covered": p.shape.covered, "raw": raw, "alternatives": alts,
            "right": right, "accuracy": acc, "body_error": body_error(seen, declared),
            "surface_error": surface_error(seen, declared),
        })  # fmt: skip
    return rows


def body_error(seen: ObjectType, declared: ObjectType) -> list[float]:
    """m: how much wider than declared the body was read, per side, along x and y."""
    a, b = seen.body.box, declared.body.box
    return [round(((a.max[k] - a.min[k]) - (b.max[k] - b.min[k])) / 2, 6) for k in (0, 1)]


def surface_error(seen: ObjectType, declared: ObjectType) -> list[float]:
    """m: how much wider than declared each sized top or bottom surface (a flat face, a
    well, an opening) was read, per side, along x and y, where it was read as that shape."""
    out: list[float] = []
    for part in ("on", "under"):
        a, b = seen.parts[part], declared.parts[part]
        if a.shape == b.shape and a.size is not None and b.size is not None:
            out += [round((a.size[k] - b.size[k]) / 2, 6) for k in (0, 1)]
    return out


def size_error(
    rows: list[dict[str, object]], key: str = "body_error", quantile: float = SIZE_COVERAGE
) -> dict[str, float]:
    """A reading error per side (`key`: the body's, ``surface_error`` the surfaces'): the
    `quantile` of its magnitude on the even-numbered scenes, rounded up to 0.1 mm (the
    perceiver's ``SIZE_ERROR``, ``SURFACE_ERROR``), its signed median there, and the share
    of the odd-numbered scenes' readings it covers."""
    errors = {
        parity: np.array([e for r in rows if _index(r) % 2 == parity for e in r[key]])  # type: ignore[attr-defined]
        for parity in (0, 1)
    }
    fit, held = errors[0], np.abs(errors[1])
    bound = math.ceil(float(np.quantile(np.abs(fit), quantile)) * 1e4 - 1e-6) / 1e4
    return {
        "quantile": quantile, "metres": bound, "median_signed": float(np.median(fit)),
        "held_out_covered": float(np.mean(held <= bound + 1e-9)),
    }  # fmt: skip


def _error_lines(size: dict[str, float], what: str, constant: str) -> list[str]:
    """The page's paragraph on one reading error (`size_error`'s result)."""
    return [
        "",
        f"{what} {1000 * size['median_signed']:+.2f} mm wider than declared at the median; "
        f"{size['quantile']:.0%} of the even-numbered scenes' readings are within "
        f"**{1000 * size['metres']:.2f} mm** (`perception.confidence.{constant}`), which "
        f"covers {size['held_out_covered']:.1%} of the odd-numbered ones'.",
    ]


def collect(cache: Path, limit: int | None) -> list[dict[str, object]]:
    return cached_rows(
        SUITE, cache, scene_rows, limit=limit, file_name=lambda n: n.replace("/", "_")
    )


def _index(row: dict[str, object]) -> int:
    return int(str(row["scene"]).rsplit("/", 1)[-1])


def reliability(
    rows: list[dict[str, object]], cal: Calibration | None
) -> dict[str, list[dict[str, float]]]:
    """Per attribute and confidence bin: count, mean confidence, accuracy."""
    return {
        a: reliability_table(
            [cal(a, r["raw"][a]) if cal else r["raw"][a] for r in rows],  # type: ignore[index]
            [r["right"][a] for r in rows],  # type: ignore[index]
        )
        for a in CALIBRATED
    }


def accuracy(rows: list[dict[str, object]]) -> dict[str, float]:
    keys = ("material", "robustness", "mass", "members", "member_size")
    return {k: float(np.mean([r["right"][k] for r in rows])) for k in keys}  # type: ignore[index]


def reliability_tables(shipped: str, kept: list[str]) -> list[tuple[str, str]]:
    """(label, payload key) of the page's reliability tables: the raw confidences; the maps
    this run fits on the even-numbered scenes (`kept`), said to be shipped only when the
    package's maps are these (`shipped` "fitted"); and an earlier run's shipped maps
    ("other"), which the perceiver applies until ``--write-calibration`` replaces them."""
    maps = ", ".join(kept) or "none"
    if shipped == "fitted":
        return [("raw", "reliability_raw"),
                (f"shipped (maps for {maps}, fitted by this run)", "reliability")]  # fmt: skip
    tables = [("raw", "reliability_raw"),
              (f"fitted by this run but not shipped (maps for {maps})", "reliability")]  # fmt: skip
    if shipped == "other":
        label = "shipped (an earlier run's maps: `--write-calibration` ships this run's)"
        tables.append((label, "reliability_shipped"))
    return tables


def _markdown(payload: dict[str, object]) -> str:
    lines = [
        f"The perceiver on {SUITE} (seed 0; development data: no test split is read), "
        f"{payload['objects']} objects in {payload['scenes']} scenes "
        "(`benchmarks/perceiver_train.py`). Right: the perceived value equals the declared "
        "one (mass: the same class at the rules' thresholds 0.5 / 1.1 / 1.5 / 3.0 kg; "
        "members: the same members, Dice 1; member_size: every matched box within 1 cm).",
        "",
        "| objects | " + " | ".join(payload["accuracy"]["all"]) + " |",  # type: ignore[index]
        "|---" * 6 + "|",
    ]
    for group, acc in payload["accuracy"].items():  # type: ignore[attr-defined]
        lines.append(f"| {group} | " + " | ".join(f"{v:.3f}" for v in acc.values()) + " |")
    lines += ["", "Material confusions (declared -> perceived: count):", ""]
    for k, v in payload["confusions"].items():  # type: ignore[attr-defined]
        lines.append(f"- {k}: {v}")
    lines += _error_lines(
        payload["size_error"],  # type: ignore[arg-type]
        "Body sizes: per side along x and y, the perceived body is read",
        "SIZE_ERROR",
    )
    lines += _error_lines(
        payload["surface_error"],  # type: ignore[arg-type]
        "Top and bottom surfaces (a flat face, a well, an opening; read as the declared "
        "shape): per side along x and y, read",
        "SURFACE_ERROR",
    )
    tables = reliability_tables(payload["shipped"], payload["calibrated_attributes"])  # type: ignore[arg-type]
    for label, key in tables:
        lines += [
            "",
            f"Reliability of the {label} confidences on the odd-numbered scenes (the "
            "calibration is fitted on the even-numbered ones): per bin of confidence, "
            "objects, mean confidence, share right; ECE = expected calibration error.",
            "",
            "| attribute | bin | n | confidence | right |",
            "|---|---|---|---|---|",
        ]
        for a, table in payload[key].items():  # type: ignore[attr-defined]
            for t in table:
                if "ece" in t:
                    lines.append(f"| {a} | ECE | | {t['ece']:.3f} | |")
                else:
                    lo, hi = t["bin"]
                    lines.append(f"| {a} | {lo:.2f}–{hi:.2f} | {t['n']} | "
                                 f"{t['confidence']:.3f} | {t['accuracy']:.3f} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--limit", type=int, default=None, help="only the first N train scenes")
    ap.add_argument("--cache", type=Path, default=Path("runs/perceiver_train"))
    ap.add_argument("--results", type=Path, default=ROOT / "docs" / "results")
    ap.add_argument("--write-calibration", action="store_true",
                    help="write assets/perception/confidence_calibration.json")  # fmt: skip
    return ap


def fit_calibration(rows: list[dict[str, object]]) -> tuple[Calibration, list[str]]:
    """The isotonic maps fitted on the even-numbered scenes' raw confidences, kept only for
    the attributes whose calibration error on the odd-numbered ones they lower (material's
    posterior may be temperature-calibrated already: isotonic on half the scenes can
    overfit it); and those attributes."""
    fit = [r for r in rows if _index(r) % 2 == 0]
    held = [r for r in rows if _index(r) % 2 == 1]
    cal = Calibration.fit(
        {a: ([r["raw"][a] for r in fit], [float(r["right"][a]) for r in fit]) for a in CALIBRATED}  # type: ignore[index]
    )
    raw_rel, fitted = reliability(held, None), reliability(held, cal)
    kept = [a for a in CALIBRATED if fitted[a][-1]["ece"] < raw_rel[a][-1]["ece"]]
    return Calibration({a: cal.knots[a] for a in kept}), kept


def main() -> None:
    args = build_parser().parse_args()
    commit()
    rows = collect(args.cache, args.limit)
    held = [r for r in rows if _index(r) % 2 == 1]
    cal, kept = fit_calibration(rows)
    raw_rel = reliability(held, None)
    package = packaged_calibration()  # what the perceiver applies (before any --write)
    written = json.loads(json.dumps(cal.to_json()))
    same = package is not None and json.loads(json.dumps(package.to_json())) == written
    shipped = "fitted" if args.write_calibration or same else ("other" if package else "none")
    crowded = max(int(r["n_objects"]) for r in rows)  # type: ignore[call-overload]
    confusions: dict[str, int] = {}
    for r in rows:
        d, p = r["declared"]["material"], r["perceived"]["material"]  # type: ignore[index]
        if d != p:
            confusions[f"{d} -> {p}"] = confusions.get(f"{d} -> {p}", 0) + 1
    payload = {
        "suite": SUITE, "scenes": len({r["scene"] for r in rows}), "objects": len(rows),
        "accuracy": {
            "all": accuracy(rows),
            f"in scenes of {crowded} objects": accuracy(
                [r for r in rows if r["n_objects"] == crowded]),
            "body top under 30 % covered": accuracy([r for r in rows if r["covered"] < 0.3]),
            "body top over 30 % covered": accuracy([r for r in rows if r["covered"] >= 0.3]),
        },
        "confusions": dict(sorted(confusions.items(), key=lambda kv: -kv[1])),
        "reliability_raw": raw_rel,
        "reliability": reliability(held, cal),
        # "fitted": the package ships this run's maps; "other": an earlier run's; "none"
        "shipped": shipped,
        **({"reliability_shipped": reliability(held, package)} if shipped == "other" else {}),
        "calibrated_attributes": kept,
        "size_error": size_error(rows),
        "surface_error": size_error(rows, "surface_error", SURFACE_COVERAGE),
        "calibration": cal.to_json(),
    }  # fmt: skip
    md = _markdown(payload)
    print(md)
    args.results.mkdir(parents=True, exist_ok=True)
    write_markdown(args.results / "perceiver-train.md", md)
    write_json(args.results / "perceiver-train.json", payload, indent=2)
    if args.write_calibration:
        path = ROOT / "assets" / Path(*CALIBRATION_FILE)
        path.write_text(json.dumps(cal.to_json(), indent=1) + "\n")


if __name__ == "__main__":
    main()
