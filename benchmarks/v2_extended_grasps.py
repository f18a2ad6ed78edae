"""How many procedural-v2 goals need a grasp that only the extended domain grants.

Every achievable goal of the split file (labelled under `spec.DOMAIN`, ``utamp2x``: the rim
pinches on bowls, plates and pans of issue 39) is planned again with the paper's domain
(``utamp2-rules``, the same rules without the extended grasps). A goal the paper's domain
cannot reach needs an extended grasp; the table counts them per split and template, and the
families of the objects the ``utamp2x`` plan picks up in those scenes. Writes
``<out>.md`` / ``<out>.json`` with the commit and the command.

    python benchmarks/v2_extended_grasps.py [--out docs/results/v2_extended_grasps]
"""

from __future__ import annotations

import argparse
from collections import Counter, defaultdict
from typing import Any

from utamp_gym.planning.methods import plan_scene
from utamp_gym.provenance import provenance, write_json, write_markdown
from utamp_gym.suites.procedural_v2 import available_splits, split_scenes
from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD

PAPER_METHOD = "utamp2-rules"


def _picked(plan: tuple[str, ...]) -> list[str]:
    """The objects a plan picks up (the first argument of its pick actions)."""
    return [a[1:-1].split()[1] for a in plan if a.startswith("(pick")]


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--out", default="docs/results/v2_extended_grasps")
    return ap


def main() -> int:
    args = build_parser().parse_args()
    per: dict[str, Counter[str]] = defaultdict(Counter)
    families: Counter[str] = Counter()
    scenes: list[dict[str, Any]] = []
    for split in available_splits():
        for g in split_scenes(split):
            if not g.achievable:
                continue
            per[split]["achievable"] += 1
            paper = plan_scene(g.scene, PAPER_METHOD, timeout=args.timeout)
            if paper.solved:
                continue
            ext = plan_scene(g.scene, LABEL_METHOD, timeout=args.timeout)
            index = {o: i for i, o in enumerate(g.scene.object_names)}
            picked = sorted({g.families[index[o]] for o in _picked(ext.plan) if o in index})
            families.update(picked)
            per[split]["extended only"] += 1
            per[split][g.template] += 1
            scenes.append({"scene": g.scene.name, "template": g.template,
                           "picked_families": picked, "timed_out": paper.timed_out})  # fmt: skip
    total = sum(c["achievable"] for c in per.values())
    ext_total = sum(c["extended only"] for c in per.values())
    lines = [
        f"Achievable procedural-v2 goals ({LABEL_METHOD}) that {PAPER_METHOD} cannot reach: "
        f"{ext_total} of {total}",
        "",
        "| split | achievable | need an extended grasp | by template |",
        "|---|---|---|---|",
    ]
    for split, c in per.items():
        by = ", ".join(f"{t} {n}" for t, n in sorted(c.items())
                       if t not in ("achievable", "extended only"))  # fmt: skip
        lines.append(f"| {split} | {c['achievable']} | {c['extended only']} | {by or '-'} |")
    lines += ["", "Families the utamp2x plan picks up in those scenes (scenes per family): "
              + (", ".join(f"{f} {n}" for f, n in families.most_common()) or "none")]  # fmt: skip
    text = "\n".join(lines) + "\n"
    print(text)
    write_markdown(f"{args.out}.md", text, provenance())
    write_json(f"{args.out}.json", {"per_split": {k: dict(v) for k, v in per.items()},
                                    "scenes": scenes, "args": vars(args)})  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
