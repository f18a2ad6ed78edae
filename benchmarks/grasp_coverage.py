"""Which kitchenware the rules make liftable, per family, and what physics says about it.

    nice -n 5 python benchmarks/grasp_coverage.py [--instances 40] [--physics 40]
        [--base 2c0b0d1] [--out docs/results/grasp_coverage]

Rules: over the first `--instances` instances of every family (`object_facts` on
``generate(family, "v1", seed)``), how many the rules make liftable (a ``canLift`` fact)
under the paper's domain (``utamp2``) and the extended one (``utamp2x``: rim pinches,
`utamp_gym.affordances.rim`), in all and among those whose mass is within the payload the
rules lift (`PAYLOAD` x `LIFT_FRACTION`). ``--base`` measures the paper's domain again on an
earlier commit, checked out as a detached worktree for the run ("before").

The extended domain lifts flat boards also by sliding them to the table's edge and pinching
them there (``canEdgePinch``, `utamp_gym.affordances.edge`): "utamp2x + edge" counts them;
`benchmarks/edge_slide.py` measures that action in physics.

Physics (``--physics N``, 0: none): each of the first N instances alone on the table (one
object, two slots) in MuJoCo, without pose noise. Every grasp from above that the extended
rules allow is picked and placed on a slot the scene's rules grant it (the other slot, else
back on its own: `symbolic.slots.admits`, whose reach geometry the placement shares; none:
only picked) (precision: both succeed); every other grasp from above the hand could close on
(each member, each finger pair) is picked (recall: the share of forbidden picks physics
lifts), and a forbidden pick physics lifts is placed as an allowed one would be (a grant is
right only if the placement succeeds too: "lifted and placed"). Writes ``<out>.json`` and
``<out>.md``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
from compare import base_worktree, git
from result_page import share, write_page

from utamp_gym.affordances.rules import LIFT_FRACTION, PAYLOAD, object_facts
from utamp_gym.kitchenware import FAMILIES, family, generate, type_table
from utamp_gym.kitchenware.params import draw
from utamp_gym.provenance import commit
from utamp_gym.scene.io import scene_from_dict
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.slots import admits

IN_PAYLOAD = PAYLOAD * LIFT_FRACTION  # kg
TARGET, FORBIDDEN_TARGET = 0.98, 0.05
#: the paper's rules on any commit: (family, seed, mass, liftable) per line
RULES_SNIPPET = """
import json, sys
from utamp_gym.affordances.rules import object_facts
from utamp_gym.kitchenware import FAMILIES, generate
for fam in FAMILIES:
    for s in range(int(sys.argv[1])):
        t = generate(fam, "v1", s)
        print(json.dumps([fam, s, t.mass, any(f[0] == "canLift" for f in object_facts(t))]))
"""


def rules_table(n: int) -> dict[str, dict[str, int]]:
    """Per family: instances, in payload, liftable under utamp2 / utamp2x (all, in payload)."""
    out: dict[str, dict[str, int]] = {}
    for fam in FAMILIES:
        row = defaultdict(int)
        for s in range(n):
            t = generate(fam, "v1", s)
            inside = t.mass <= IN_PAYLOAD
            row["n"] += 1
            row["in_payload"] += inside
            for domain, ext in (("utamp2", False), ("utamp2x", True)):
                facts = object_facts(t, ext)
                lift = any(f[0] == "canLift" for f in facts)
                row[domain] += lift
                row[f"{domain}_in_payload"] += lift and inside
            edge = lift or any(f[0] == "canEdgePinch" for f in facts)  # utamp2x's facts
            row["utamp2x_edge"] += edge
            row["utamp2x_edge_in_payload"] += edge and inside
        out[fam] = dict(row)
    return out


def base_table(base: str, n: int) -> dict[str, dict[str, int]]:
    """The paper's rules at commit `base` (its own worktree, its own interpreter run)."""
    with base_worktree(base, "grasp-coverage-") as tree:
        env = {"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"}
        text = subprocess.run(
            [sys.executable, "-c", RULES_SNIPPET, str(n)],
            cwd=tree, env=env, check=True, capture_output=True, text=True,
        ).stdout  # fmt: skip
    out: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for line in text.splitlines():
        fam, _, mass, lift = json.loads(line)
        out[fam]["n"] += 1
        out[fam]["utamp2"] += lift
        out[fam]["utamp2_in_payload"] += lift and mass <= IN_PAYLOAD
    return {k: dict(v) for k, v in out.items()}


def lone_data(table: dict[str, Any], name: str = "lone") -> dict[str, Any]:
    """Scene data: one object ``obj`` of the type table `table` alone on slot1 of a two-slot
    table (the tests add a goal or a second object to it)."""
    return {
        "name": name, "types": {"obj": table},
        "workspace": {"min": [0.0, -0.6, 0.0], "max": [0.82, 0.6, 0.7]},
        "slots": [
            {"name": "slot1", "position": [0.5, -0.18], "min": [0.2, -0.5], "max": [0.8, 0.08]},
            {"name": "slot2", "position": [0.5, 0.3], "min": [0.2, 0.08], "max": [0.8, 0.6]},
        ],
        "objects": [{"name": "obj", "type": "obj", "on": "slot1"}],
    }  # fmt: skip


def lone_scene(fam: str, seed: int) -> Scene:
    """Instance `seed` of `fam` alone on slot1 of a two-slot table (`lone_data`)."""
    table = type_table(family(fam), draw(family(fam), "v1", seed))
    return scene_from_dict(lone_data(table, f"lone-{fam}-{seed}"))


def candidates(fam: str, seed: int) -> list[tuple[str, str, str, bool]]:
    """(member, finger1, finger2, allowed under utamp2x) for every grasp from above."""
    t = generate(fam, "v1", seed)
    facts = object_facts(t, True)
    lift = {f[2] for f in facts if f[0] == "canLift"}
    out = []
    for m in t.members:
        for f1, f2 in (("left", "right"), ("front", "back")):
            allowed = ("canGraspFrom", t.name, m, "on", f1, f2) in facts and m in lift
            out.append((m, f1, f2, allowed))
    return out


def place_slot(fam: str, seed: int) -> str:
    """The slot the scene's rules grant the lone instance (`symbolic.slots.admits`, resting
    on its ``under``): slot2, else slot1 (put back), else "" (none: it is only picked)."""
    scene = lone_scene(fam, seed)
    t = scene.type_of("obj")
    return next((s.name for s in (scene.slot("slot2"), scene.slot("slot1"))
                 if admits(scene, s, t, "under")), "")  # fmt: skip


def try_grasp(sim: Any, fam: str, seed: int, member: str, f1: str, f2: str, place: str) -> str:
    """ "" if the pick (and the placement on slot `place`, if any) succeeded, else why not."""
    import numpy as np

    try:
        sim.reset(lone_scene(fam, seed), np.random.default_rng(seed))
    except Exception as exc:  # a scene the table cannot hold: reported, not counted
        return f"scene: {exc}"
    grasp = f"obj obj-{member} on {f1} {f2} under on"
    res = sim.execute(f"(pick-support {grasp} slot1 under on)")
    if not res.success or not place:
        return "" if res.success else res.reason or "failed"
    res = sim.execute(f"(place-support {grasp} under {place} under on)")
    return "" if res.success else res.reason or "failed"


def physics_table(
    n: int,
) -> tuple[dict[str, dict[str, int]], list[dict[str, Any]], list[dict[str, Any]]]:
    """Per family the counts, the allowed grasps physics failed and the forbidden ones it
    lifted (the picks the rules miss)."""
    from utamp_gym.sim.backend import MujocoBackend

    sim = MujocoBackend(pose_noise=0.0)
    rows: dict[str, dict[str, int]] = {}
    cases, missed = [], []
    try:
        for fam in FAMILIES:
            row = defaultdict(int)
            for seed in range(n):
                slot = place_slot(fam, seed)
                for member, f1, f2, allowed in candidates(fam, seed):
                    why = try_grasp(sim, fam, seed, member, f1, f2, slot if allowed else "")
                    if why.startswith("scene:"):
                        row["scene_errors"] += 1
                        continue
                    key = "allowed" if allowed else "forbidden"
                    row[key] += 1
                    row["placed_back"] += allowed and slot == "slot1"
                    row["pick_only"] += allowed and not slot
                    row[f"{key}_ok"] += not why
                    if allowed and why:
                        cases.append({"family": fam, "seed": seed, "member": member,
                                      "fingers": f"{f1}/{f2}", "reason": why})  # fmt: skip
                    if not allowed and not why:  # lifted anyway: does it place too?
                        placed = not slot or not try_grasp(sim, fam, seed, member, f1, f2, slot)
                        row["forbidden_placed"] += placed
                        missed.append({"family": fam, "seed": seed, "member": member,
                                       "fingers": f"{f1}/{f2}", "placed": placed})  # fmt: skip
                    print(f"{fam:15s} {seed:3d} {member:12s} {f1}/{f2} "
                          f"{key:9s} {'ok' if not why else why[:80]}", flush=True)  # fmt: skip
            rows[fam] = dict(row)
    finally:
        sim.close()
    return rows, cases, missed


def markdown(data: dict[str, Any]) -> str:
    n = data["instances"]
    lines = [
        "<!-- written by benchmarks/grasp_coverage.py; do not edit -->",
        "",
        f"Liftable kitchenware per family over the first {n} instances of procedural v1 "
        f'(`object_facts` on `generate(family, "v1", seed)`). In payload: mass at most '
        f"{IN_PAYLOAD:.1f} kg, what the rules lift with a wrapping grasp. Before: the paper's "
        f"domain at commit `{data['base']}`; utamp2: the paper's domain on this commit; "
        "utamp2x: the extended domain (rim pinches); + edge: with boards slid to the table's "
        "edge and pinched there (`slide-edge`, `docs/results/edge_slide.md`).",
        "",
        "| family | in payload | before (utamp2) | utamp2 | utamp2x | utamp2x + edge "
        "| utamp2x + edge, all |",
        "|---|---|---|---|---|---|---|",
    ]
    for fam, r in data["rules"].items():
        b = data["before"].get(fam, {}) if data["before"] else {}
        before = share(b.get("utamp2_in_payload", 0), r["in_payload"]) if b else "–"
        lines.append(
            f"| {fam} | {r['in_payload']}/{r['n']} | {before} | "
            f"{share(r['utamp2_in_payload'], r['in_payload'])} | "
            f"{share(r['utamp2x_in_payload'], r['in_payload'])} | "
            f"{share(r['utamp2x_edge_in_payload'], r['in_payload'])} | "
            f"{share(r['utamp2x_edge'], r['n'])} |"
        )
    if data["physics"]:
        m = data["physics_instances"]
        lines += [
            "",
            f"Physics, each of the first {m} instances alone on the table (MuJoCo, no pose "
            "noise): every grasp from above the extended rules allow, picked and placed on the "
            "other slot, or back on its own where the scene's rules grant only that (placed "
            "back), or only picked where they grant neither (pick only) "
            f"(target ≥ {TARGET:.0%}); every other grasp from above, picked (physics lifting "
            f"it is a pick the rules miss; target ≤ {FORBIDDEN_TARGET:.0%}), and each one "
            "lifted is placed as an allowed one would be (lifted and placed: a pick the rules "
            "could have granted).",
            "",
            "| family | allowed: picked and placed | of them placed back, pick only "
            "| forbidden: lifted anyway | forbidden: lifted and placed anyway |",
            "|---|---|---|---|---|",
        ]
        tot = defaultdict(int)
        for fam, r in data["physics"].items():
            for k in ("allowed", "allowed_ok", "forbidden", "forbidden_ok", "forbidden_placed"):
                tot[k] += r.get(k, 0)
            lines.append(
                f"| {fam} | {share(r.get('allowed_ok', 0), r.get('allowed', 0))} | "
                f"{r.get('placed_back', 0)}, {r.get('pick_only', 0)} | "
                f"{share(r.get('forbidden_ok', 0), r.get('forbidden', 0))} | "
                f"{share(r.get('forbidden_placed', 0), r.get('forbidden', 0))} |"
            )
        lines.append(
            f"| **all** | {share(tot['allowed_ok'], tot['allowed'])} | | "
            f"{share(tot['forbidden_ok'], tot['forbidden'])} | "
            f"{share(tot['forbidden_placed'], tot['forbidden'])} |"
        )
        if data["failures"]:
            lines += ["", "Allowed grasps physics failed:", ""]
            lines += [
                f"- {c['family']} {c['seed']} {c['member']} ({c['fingers']}): {c['reason']}"
                for c in data["failures"]
            ]
        if data.get("missed"):
            lines += ["", "Forbidden grasps physics lifted (the picks the rules miss; "
                      "not placed: the placement failed):", ""]  # fmt: skip
            for fam in dict.fromkeys(c["family"] for c in data["missed"]):
                cs = [c for c in data["missed"] if c["family"] == fam]
                grasps = ", ".join(
                    f"{c['seed']} {c['member']} ({c['fingers']}"
                    f"{'' if c.get('placed', True) else ', not placed'})"
                    for c in cs
                )
                lines.append(f"- {fam}: {grasps}")
    lines.append("")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=40)
    ap.add_argument("--physics", type=int, default=0, help="instances per family in physics")
    ap.add_argument("--base", default="", help="an earlier commit for the 'before' column")
    ap.add_argument("--out", default="docs/results/grasp_coverage")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # fixed at the start of the run
    start = time.perf_counter()
    data: dict[str, Any] = {
        "instances": args.instances,
        "in_payload_kg": IN_PAYLOAD,
        "base": git("rev-parse", "--short", args.base) if args.base else "",
        "before": base_table(args.base, args.instances) if args.base else {},
        "rules": rules_table(args.instances),
        "physics_instances": args.physics,
        "physics": {},
        "failures": [],
        "missed": [],
    }
    if args.physics:
        data["physics"], data["failures"], data["missed"] = physics_table(args.physics)
    write_page(args.out, data, markdown, start)


if __name__ == "__main__":
    main()
