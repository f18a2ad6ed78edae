"""Boards slid to the table's near edge and pinched there (issue #39, ``slide-edge``): the
rules' verdict per family, and what physics does with it.

    nice -n 5 python benchmarks/edge_slide.py [--instances 40] [--physics 40]
        [--out docs/results/edge_slide]

Rules: over the first `--instances` instances of every family (``generate(family, "v1",
seed)``), how many `utamp_gym.affordances.edge.edge_pinch_refusal` grants (the extended
domain ``utamp2x``'s ``canEdgePinch``), and how many are then liftable under ``utamp2x`` in
all (a ``canLift`` fact or the edge pinch), among all and among those whose mass is within
the payload the rules lift (`grasp_coverage.IN_PAYLOAD`).

Physics (``--physics N``, 0: none): for every family with an instance the rule does not
refuse for its shape (a slab: neither ``edge-slab`` nor ``edge-thickness``), each of the first
N instances alone on the table (`grasp_coverage.lone_scene`, MuJoCo, no pose noise) is slid
to the edge and lifted (``slide-edge``), and if the rule allows it, put on the other slot
(``place-edge``); allowed ones that succeed measure the rule's precision, refused ones that
are lifted the picks it misses. Writes ``<out>.json`` and ``<out>.md``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
from grasp_coverage import FORBIDDEN_TARGET, IN_PAYLOAD, TARGET, lone_scene
from result_page import share, write_page

from utamp_gym.affordances.edge import DEEP_PAD_IN, PAD_IN, edge_depth, edge_pinch_refusal
from utamp_gym.affordances.hand import G
from utamp_gym.affordances.rules import object_facts
from utamp_gym.affordances.solids import centre_of_mass
from utamp_gym.kitchenware import FAMILIES, generate
from utamp_gym.provenance import commit

SHAPE_RULES = ("edge-slab", "edge-thickness")
SLIDE = "(slide-edge obj obj-body back on under back on slot1 under on)"
PLACE = "(place-edge obj obj-body back on under back on under slot2 back on)"


def rules_table(n: int) -> dict[str, dict[str, Any]]:
    """Per family: instances, in payload, edge pinch granted, liftable under utamp2x with
    it (all, in payload), refusals by rule."""
    out: dict[str, dict[str, Any]] = {}
    for fam in FAMILIES:
        row: dict[str, Any] = defaultdict(int)
        why: dict[str, int] = defaultdict(int)
        for s in range(n):
            t = generate(fam, "v1", s)
            inside = t.mass <= IN_PAYLOAD
            facts = object_facts(t, True)
            edge = any(f[0] == "canEdgePinch" for f in facts)
            lift = edge or any(f[0] == "canLift" for f in facts)
            row["n"] += 1
            row["in_payload"] += inside
            row["edge"] += edge
            row["edge_in_payload"] += edge and inside
            row["liftable"] += lift
            row["liftable_in_payload"] += lift and inside
            refusal = edge_pinch_refusal(t)
            why[refusal.rule if refusal else "granted"] += 1
        out[fam] = {**row, "why": dict(why)}
    return out


def pinch_moment(fam: str, seed: int) -> tuple[float, float, float, float]:
    """(mass kg, thickness m, moment N m of the weight about the pinch, the pinch's depth m:
    `edge_depth`, as the skill pinches it) of an instance."""
    t = generate(fam, "v1", seed)
    cx, cy = centre_of_mass(t)
    x0 = float(t.bbox.min[0])
    end = [m for m in t.members.values() if m.box.min[0] <= x0 + 1e-6]
    py = float(end[0].box.center_xy[1]) if end else 0.0
    depth = edge_depth(t)
    lever = math.hypot(cx - (x0 + depth), cy - py)
    return t.mass, float(t.bbox.size[2]), t.mass * G * lever, depth


def physics_table(n: int, families: list[str]) -> list[dict[str, Any]]:
    import numpy as np

    from utamp_gym.sim.backend import MujocoBackend

    sim = MujocoBackend(pose_noise=0.0)
    cases = []
    try:
        for fam in families:
            for seed in range(n):
                refusal = edge_pinch_refusal(generate(fam, "v1", seed))
                mass, thick, moment, depth = pinch_moment(fam, seed)
                case = {"family": fam, "seed": seed, "allowed": refusal is None,
                        "rule": refusal.rule if refusal else "", "mass": round(mass, 3),
                        "thickness": round(thick, 4), "moment": round(moment, 3),
                        "depth": depth}  # fmt: skip
                try:
                    sim.reset(lone_scene(fam, seed), np.random.default_rng(seed))
                except Exception as exc:  # a scene the table cannot hold: reported
                    case.update(ok=False, reason=f"scene: {exc}")
                    cases.append(case)
                    continue
                res = sim.execute(SLIDE)
                case.update(ok=res.success, reason=res.reason or "", placed=False)
                if res.success and refusal is None:  # allowed: put on the other slot too
                    placed = sim.execute(PLACE)
                    case.update(placed=placed.success, place_reason=placed.reason or "")
                cases.append(case)
                verdict = "allowed" if refusal is None else refusal.rule
                outcome = "ok" if res.success else res.reason
                print(f"{fam:15s} {seed:3d} {verdict:9s} {moment:.2f} N m {outcome}", flush=True)
    finally:
        sim.close()
    return cases


def markdown(data: dict[str, Any]) -> str:
    n = data["instances"]
    lines = [
        "<!-- written by benchmarks/edge_slide.py; do not edit -->",
        "",
        f"Slid to the table's edge and pinched there (`slide-edge`, extended domain), over "
        f"the first {n} instances of procedural v1 per family: the edge pinch the rules grant "
        f"(`utamp_gym.affordances.edge`), and what is liftable under utamp2x with it (a "
        f"`canLift` fact or the edge pinch). In payload: mass at most {IN_PAYLOAD:.1f} kg. "
        "Families the rule refuses for their shape alone (no flat slab) are left out.",
        "",
        "| family | in payload | edge pinch | edge pinch, in payload | liftable in utamp2x "
        "| liftable, in payload | refused by |",
        "|---|---|---|---|---|---|---|",
    ]
    for fam, r in data["rules"].items():
        if set(r["why"]) <= set(SHAPE_RULES):
            continue
        why = ", ".join(f"{k} {v}" for k, v in sorted(r["why"].items()) if k != "granted")
        lines.append(
            f"| {fam} | {r['in_payload']}/{r['n']} | {share(r['edge'], r['n'])} | "
            f"{share(r['edge_in_payload'], r['in_payload'])} | {share(r['liftable'], r['n'])} "
            f"| {share(r['liftable_in_payload'], r['in_payload'])} | {why or '–'} |"
        )
    if data["physics"]:
        m = data["physics_instances"]
        lines += [
            "",
            f"Physics, each of the first {m} instances alone on the table (MuJoCo, no pose "
            "noise), slid to the edge, pinched and lifted (`slide-edge`; "
            f"{PAD_IN * 1000:.0f} mm inside its end, or {DEEP_PAD_IN * 1000:.0f} mm, slid "
            "further out, where the weight would turn it out of the shallower pinch: "
            "`edge_depth`; the moments are about the pinch made): allowed by the rule, "
            "lifted, then put on the other slot (`place-edge`) "
            f"(target ≥ {TARGET:.0%}); refused (beyond the shape), lifted anyway "
            f"(target ≤ {FORBIDDEN_TARGET:.0%}).",
            "",
            "| family | allowed: lifted | allowed: lifted and placed | refused: lifted anyway "
            "| pinched deep | moments lifted (N m) | moments failed (N m) |",
            "|---|---|---|---|---|---|---|",
        ]
        for fam in dict.fromkeys(c["family"] for c in data["physics"]):
            cs = [c for c in data["physics"] if c["family"] == fam]
            allowed = [c for c in cs if c["allowed"]]
            refused = [c for c in cs if not c["allowed"] and c["rule"] not in SHAPE_RULES]
            ok = [c["moment"] for c in cs if c["ok"]]
            bad = [c["moment"] for c in cs if not c["ok"]]
            span = lambda xs: f"{min(xs):.2f}–{max(xs):.2f}" if xs else "–"  # noqa: E731
            lines.append(
                f"| {fam} | {share(sum(c['ok'] for c in allowed), len(allowed))} | "
                f"{share(sum(c['placed'] for c in allowed), len(allowed))} | "
                f"{share(sum(c['ok'] for c in refused), len(refused))} | "
                f"{sum(c.get('depth', PAD_IN) > PAD_IN for c in cs)} | {span(ok)} | {span(bad)} |"
            )
        fails = [c for c in data["physics"] if c["allowed"] and not c["placed"]]
        if fails:
            lines += ["", "Allowed slides and placements physics failed:", ""]
            lines += [f"- {c['family']} {c['seed']} ({c['moment']:.2f} N m): "
                      f"{c['reason'] or c.get('place_reason', '')}" for c in fails]  # fmt: skip
    lines.append("")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=40)
    ap.add_argument("--physics", type=int, default=0, help="instances per family in physics")
    ap.add_argument("--out", default="docs/results/edge_slide")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # fixed at the start of the run
    start = time.perf_counter()
    rules = rules_table(args.instances)
    slabs = [f for f, r in rules.items() if not set(r["why"]) <= set(SHAPE_RULES)]
    data: dict[str, Any] = {
        "instances": args.instances,
        "in_payload_kg": IN_PAYLOAD,
        "rules": rules,
        "physics_instances": args.physics,
        "physics": physics_table(args.physics, slabs) if args.physics else [],
    }
    write_page(args.out, data, markdown, start)


if __name__ == "__main__":
    main()
