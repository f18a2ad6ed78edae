"""Which perceived readings break the rules' facts, per kitchenware family, on
procedural-v1/train (development data: no test split is read): docs/results/perceived-train-
facts.{md,json}.

Every ``--every``-th train scene is reset with its episode seed (seed 0, as `utamp eval` does)
and perceived (`methods.perceived.perceive_scene`); the rules' facts on each object's
perceived type, renamed to the declared members (`PerceivedScene.declared_facts`), are
compared with the ground truth on its declared type. An object is *right* when none of the
facts naming it differs (a support fact names both objects: it counts for both). Per family:
objects right, the predicates most often added (+) or missed (-), and the body's size error
(perceived minus declared, mm; median over the family's objects whose body shape was read
right). Per number of objects in the scene: objects right, scenes with every object right.
Rows are cached per scene under ``--cache`` (resumable; ``--part I/N`` for parallel processes,
``--report`` to write the tables from the cache alone).

    python benchmarks/perceived_train_facts.py [--every 3] [--part 1/2] [--report]
        [--cache runs/perceived_train_facts] [--results docs/results]
"""

from __future__ import annotations

import argparse
import collections
import json
from pathlib import Path

import numpy as np

from utamp_gym.affordances.sources import ground_truth_for, plan_affordances
from utamp_gym.methods.perceived import perceive_scene
from utamp_gym.provenance import commit, write_json, write_markdown
from utamp_gym.suites import suite_scenes

ROOT = Path(__file__).resolve().parents[1]
SUITE = "procedural-v1/train"


def scene_row(scene) -> dict[str, object]:  # type: ignore[no-untyped-def]
    """Per object of `scene`: its family, the facts added and missed, the body size error."""
    ps = perceive_scene(scene)
    truth = ground_truth_for(scene)
    facts = ps.declared_facts(plan_affordances(ps.planning))
    objects = []
    for o in scene.objects:
        declared, seen = scene.type_of(o.name), ps.types[o.name]
        mine_t = {f for f in truth if declared.name in f[1:]}
        mine_p = {f for f in facts if declared.name in f[1:]}
        same_geom = declared.body.geom == seen.body.geom
        error = (np.asarray(seen.body.box.size) - np.asarray(declared.body.box.size)) * 1000
        objects.append({
            "object": o.name, "family": declared.name.split("-v1-")[0],
            "added": sorted(f[0] for f in mine_p - mine_t),
            "missed": sorted(f[0] for f in mine_t - mine_p),
            "body_geom_right": same_geom,
            "body_error_mm": [round(float(e), 2) for e in error] if same_geom else None,
        })  # fmt: skip
    return {"scene": scene.name, "n_objects": scene.n_objects, "objects": objects}


def collect(cache: Path, every: int, part: tuple[int, int], compute: bool) -> list[dict]:
    cache.mkdir(parents=True, exist_ok=True)
    i, n = part
    rows = []
    for k, scene in enumerate(suite_scenes(SUITE)[::every]):
        path = cache / (scene.name.rsplit("/", 1)[-1] + ".json")
        if compute and k % n == i - 1 and not path.exists():
            path.write_text(json.dumps(scene_row(scene)))
        if path.exists():
            rows.append(json.loads(path.read_text()))
    return rows


def tables(rows: list[dict]) -> dict[str, object]:
    fam: dict[str, dict] = {}
    by_n: dict[int, list[int]] = {}
    for r in rows:
        right = [not (o["added"] or o["missed"]) for o in r["objects"]]
        cell = by_n.setdefault(int(r["n_objects"]), [0, 0, 0, 0])
        cell[0] += sum(right)
        cell[1] += len(right)
        cell[2] += all(right)
        cell[3] += 1
        for o, ok in zip(r["objects"], right, strict=True):
            f = fam.setdefault(o["family"], {"right": 0, "objects": 0, "errors": [],
                                             "facts": collections.Counter()})  # fmt: skip
            f["right"] += ok
            f["objects"] += 1
            f["facts"].update("+" + p for p in o["added"])
            f["facts"].update("-" + p for p in o["missed"])
            if o["body_error_mm"] is not None:
                f["errors"].append(o["body_error_mm"])
    families = {
        name: {
            "right": f["right"], "objects": f["objects"],
            "facts": dict(f["facts"].most_common(5)),
            "body_error_mm": np.median(f["errors"], axis=0).round(1).tolist() if f["errors"]
            else None,
        }
        for name, f in sorted(fam.items(), key=lambda kv: kv[1]["right"] / kv[1]["objects"])
    }  # fmt: skip
    return {
        "scenes": len(rows),
        "scenes_all_right": sum(v[2] for v in by_n.values()),
        "families": families,
        "by_objects": {str(k): v for k, v in sorted(by_n.items())},
    }


def _markdown(t: dict, every: int) -> str:
    lines = [
        f"The perceiver's facts on one scene in {every} of {SUITE} (development data: no "
        f"test split is read; `benchmarks/perceived_train_facts.py`): scenes with every "
        f"object's facts right **{t['scenes_all_right']}/{t['scenes']}**. An object is right "
        "when no fact naming it differs from the rules on its declared type; + a predicate "
        "the perceived type adds, - one it misses; body error: perceived minus declared size "
        "(x, y, z; mm, median).",
        "",
        "| family | objects right | facts most often wrong | body error (mm) |",
        "|---|---|---|---|",
    ]
    for name, f in t["families"].items():
        facts = ", ".join(f"{k} {v}" for k, v in f["facts"].items()) or "–"
        err = (
            "–"
            if f["body_error_mm"] is None
            else " / ".join(f"{e:+.1f}" for e in f["body_error_mm"])
        )
        lines.append(f"| {name} | {f['right']}/{f['objects']} | {facts} | {err} |")
    lines += ["", "| objects in the scene | objects right | scenes with every object right |",
              "|---|---|---|"]  # fmt: skip
    for n, (ok, objs, all_ok, scenes) in t["by_objects"].items():
        lines.append(f"| {n} | {ok}/{objs} | {all_ok}/{scenes} |")
    return "\n".join(lines) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--every", type=int, default=3, help="every N-th train scene")
    ap.add_argument("--part", default="1/1", help="I/N: compute this part of the scenes")
    ap.add_argument("--report", action="store_true", help="only write the tables from the cache")
    ap.add_argument("--cache", type=Path, default=Path("runs/perceived_train_facts"))
    ap.add_argument("--results", type=Path, default=ROOT / "docs" / "results")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()
    part = tuple(int(x) for x in args.part.split("/"))
    rows = collect(args.cache, args.every, part, not args.report)  # type: ignore[arg-type]
    if not args.report and part != (1, 1):
        return  # one part of a parallel run: the tables come from --report
    t = tables(rows)
    md = _markdown(t, args.every)
    print(md)
    args.results.mkdir(parents=True, exist_ok=True)
    write_markdown(args.results / "perceived-train-facts.md", md)
    write_json(args.results / "perceived-train-facts.json", {"every": args.every, **t}, indent=2)


if __name__ == "__main__":
    main()
