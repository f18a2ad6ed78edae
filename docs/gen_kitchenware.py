"""Pictures and parameter tables of the procedural kitchenware families for docs/procedural.md.

    python docs/gen_kitchenware.py [--instances 8] [--out docs]

For each family (`utamp_gym.kitchenware.FAMILIES`) it renders a grid of sampled instances
(seeds 0, 1, ...), each built in MuJoCo from its attributes exactly as the simulator builds it
(`utamp_gym.sim.world.build_world`), and writes ``docs/images/kitchenware/<family>.png``. It
also writes ``docs/results/kitchenware_families.md``: per family its materials and each
parameter's sampled range (and the wider range real products span, where the table or the
hand narrowed it) with its source, all read from the code's parameter tables, and the
sources themselves; and ``docs/results/procedural_splits.md``, the splits' composition.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import mujoco
import numpy as np

from utamp_gym.kitchenware import FAMILIES, generate
from utamp_gym.kitchenware.params import Param
from utamp_gym.kitchenware.sources import SOURCES
from utamp_gym.provenance import commit, write_markdown
from utamp_gym.scene.catalogue import load_catalogue, type_to_dict
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.sim.gl import new_renderer
from utamp_gym.sim.world import build_world

TILE = (240, 240)  # height, width of one instance's picture


def render_instance(family: str, seed: int) -> np.ndarray:
    """One instance standing alone on the table, seen from the front and above."""
    t = generate(family, "v1", seed)
    data = {
        "name": f"kitchenware-{family}-{seed}",
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "slots": [{"name": "slot1", "position": [0.5, 0.0], "size": [0.6, 0.6]}],
        "objects": [{"name": "o", "type": t.name, "on": "slot1"}],
        "types": {t.name: type_to_dict(t)},
    }
    world = build_world(scene_from_dict(data, catalogue=load_catalogue()))
    model, state = world.model, world.make_data()
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, TILE[1])
    model.vis.global_.offheight = max(model.vis.global_.offheight, TILE[0])
    camera = mujoco.MjvCamera()
    size = np.asarray(t.bbox.size)
    pose = world.info.poses["o"].position
    camera.lookat[:] = (pose[0] + t.bbox.center[0], pose[1] + t.bbox.center[1], size[2] / 2)
    camera.distance = 0.12 + 1.5 * float(max(size))
    camera.azimuth, camera.elevation = 230.0, -35.0
    renderer = new_renderer(model, *TILE)  # a working headless GL backend (utamp_gym.sim.gl)
    try:
        renderer.update_scene(state, camera=camera)
        renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SKYBOX] = 0
        return renderer.render()
    finally:
        renderer.close()


def grid(images: list[np.ndarray], columns: int = 4) -> np.ndarray:
    rows = [images[i : i + columns] for i in range(0, len(images), columns)]
    blank = np.full_like(images[0], 255)
    rows[-1] = rows[-1] + [blank] * (columns - len(rows[-1]))
    return np.concatenate([np.concatenate(r, axis=1) for r in rows], axis=0)


def _range(p: Param) -> str:
    unit = {"mm": " mm", "kg/m3": " kg/m³", "fraction": "", "count": ""}[p.unit]
    text = f"{p.lo:g}–{p.hi:g}{unit}"
    if p.real is not None:
        text += f" (real {p.real[0]:g}–{p.real[1]:g})"
    return text


def table() -> str:
    keys = sorted({p.source for f in FAMILIES.values() for p in f.params} | {
        s for f in FAMILIES.values() for s in f.sources
    })  # fmt: skip
    out = [
        "<!-- written by docs/gen_kitchenware.py from utamp_gym.kitchenware; do not edit -->",
        "",
    ]
    for name, fam in FAMILIES.items():
        mats = ", ".join(f"{m} {w:.0%}" for m, w in fam.materials)
        out += [
            f"### {name}",
            "",
            f"{fam.doc} Materials: {mats}. Sources: {', '.join(f'[{s}]' for s in fam.sources)}.",
            "",
            f"![sampled {name} instances](../images/kitchenware/{name}.png)",
            "",
            "| parameter | sampled range | what | source |",
            "|---|---|---|---|",
        ]
        for p in fam.params:
            only = f" ({', '.join(p.materials)})" if p.materials else ""
            out.append(f"| `{p.name}`{only} | {_range(p)} | {p.doc} | [{p.source}] |")
        out.append("")
    out += ["### Sources", ""]
    out += [f"* **[{k}]** {SOURCES[k]}" for k in keys]
    return "\n".join(out) + "\n"


def splits_table() -> str:
    """Per split: scenes, the achievable share, scenes per object count, objects per family."""
    from collections import Counter

    from utamp_gym.suites import PROCEDURAL_SUITES, scene_summary

    rows = {suite: scene_summary(suite) for suite in PROCEDURAL_SUITES}
    sizes = sorted({r["n_objects"] for recs in rows.values() for r in recs})
    families = sorted({f for recs in rows.values() for r in recs for f in r["families"]})
    out = [
        "<!-- written by docs/gen_kitchenware.py from utamp_gym.suites.procedural -->",
        "",
        "| split | scenes | goal unachievable (rules) | "
        + " | ".join(f"n={n}" for n in sizes)
        + " |",
        "|---|---|---|" + "---|" * len(sizes),
    ]
    for suite, recs in rows.items():
        bad = sum(not r["achievable"] for r in recs)
        by_n = Counter(r["n_objects"] for r in recs)
        out.append(
            f"| `{suite}` | {len(recs)} | {bad} ({bad / len(recs):.0%}) | "
            + " | ".join(str(by_n.get(n, 0)) for n in sizes)
            + " |"
        )
    out += [
        "",
        "Objects per family (the base included):",
        "",
        "| family | " + " | ".join(s.split("/")[1] for s in rows) + " |",
        "|---|" + "---|" * len(rows),
    ]
    for fam in families:
        counts = [sum(r["families"].count(fam) for r in recs) for recs in rows.values()]
        out.append(f"| {fam} | " + " | ".join(str(c) if c else "–" for c in counts) + " |")
    return "\n".join(out) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=8)
    ap.add_argument("--out", default="docs")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    out = Path(args.out)
    (out / "images" / "kitchenware").mkdir(parents=True, exist_ok=True)
    (out / "results").mkdir(parents=True, exist_ok=True)
    for name in FAMILIES:
        picture = grid([render_instance(name, s) for s in range(args.instances)])
        iio.imwrite(out / "images" / "kitchenware" / f"{name}.png", picture)
        print(f"{name}: {args.instances} instances", flush=True)
    write_markdown(out / "results" / "kitchenware_families.md", table())
    write_markdown(out / "results" / "procedural_splits.md", splits_table())


if __name__ == "__main__":
    main()
