"""Rules against physics on procedural states, per kitchenware family.

    nice -n 10 python benchmarks/procedural_outcomes.py [--pairs 1200] [--workers 2]
        [--splits train,test-families] [--seed 0] [--max-steps 12]
        [--out docs/results/procedural_outcomes] [--from-json] [--domain utamp2x]

The sibling of `benchmarks/outcome_model.py` on the procedural splits, where the rule parser
is the only source of affordances (the "ground truth" of a generated type is the rules'):
episodes in the physics env (``UTampKitchenProcedural-v0``, ``masks="geometric"``, MuJoCo)
on scenes drawn by the env's RNG; at every step an action is drawn among the mask-allowed
ones, with probability 1/2 among those the rules allow (their U-TAMP-2 precondition holds)
and otherwise among those they forbid; the rules' verdict is recorded, then the simulator
executes it. An episode ends at the goal, after `--max-steps` steps, or when the simulation
no longer matches the symbolic state (`outcome_model.consistent`): after a failure, or after
an action that physics carried out otherwise than its effects say (an object that ended
inside its support, not on it). The rules judge the symbolic state; a state it misdescribes
is not one to judge them on. An action that failed is not drawn again until the state
changes: from the same state it is the same (state, action) pair.

Reported per family of the object acted on (and, for placements, of the support): how
often physics succeeds where the rules allow (target >= 98 %) and where they forbid (not a
failure: the rules are conservative where physics is lucky or forgiving), with the reasons
of every allowed action physics failed. Writes ``<out>.json`` and ``<out>.md``.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import time
from collections import Counter, defaultdict
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _common import write_results
from outcome_model import _physics_class, consistent, draw_action, episodes, symbolic_supports

from utamp_gym.affordances.rules import PALM_PARTS, pick_refusal
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.provenance import commit
from utamp_gym.sim.decode import GraspSymbols, grasp_candidates
from utamp_gym.suites import procedural, resolve_scene
from utamp_gym.symbolic.outcome import OutcomeModel, truth_atoms

TARGET = 0.98  # physics must succeed on this share of the actions the rules allow, per family
_X = np.array([1.0, 0.0, 0.0])
FORBIDDEN_PICKS = 0.05  # ... and on at most this share of the picks they forbid (issue #39)


@dataclass(frozen=True)
class Pair:
    """One (state, action) pair: the rules' verdict and what physics did."""

    split: str
    scene: str
    step: int
    action: str
    kind: str  # pick-support | place-support | slide-support
    family: str  # of the object acted on
    support_family: str  # of what it is placed on ("" for a slot or a pick)
    allowed: bool
    rules_reason: str
    physics: bool
    physics_reason: str
    step_s: float
    #: an earlier action of the episode was one the rules forbid and it changed the state:
    #: physics carried it out (a tumbler set upside down over another) or it let an object
    #: fall (beside another, touching it) -- a state the rules never lead to
    after_forbidden: bool = False


def _families(scene_name: str) -> dict[str, str]:
    parsed = procedural.parse_name(scene_name)
    assert parsed is not None, scene_name
    g = procedural.split_scene(*parsed)
    return {o.name: f for o, f in zip(g.scene.objects, g.families, strict=True)}


def pick_refusal_kind(scene_name: str, action: str, reason: str, domain: str) -> str:
    """Why the rules forbid a pick, as one word for the report: ``finger order`` when the
    grasp is granted under its other finger order and both orders give the same grasp poses
    (the hand tries both finger-axis signs, `sim.decode.grasp_candidates`; the measured grasp
    is named in the canonical order, `sim.physical.measured_grasp`); ``side grasp`` for the
    palm on a side part (the rules grant the palm on the ``on`` / ``under`` part only,
    `PALM_PARTS`: from above, upright or inverted); else the rule that refuses it
    (`affordances.rules.pick_refusal`: ``grip-width``, ``covered``, ...), ``payload`` for
    ``canLift``, ``facts`` when only `object_facts` leaves it out."""
    if reason.startswith("canLift"):
        return "payload"
    _, obj, member, palm, f1, f2, *_ = action.strip("()").split()
    scene = resolve_scene(scene_name)
    t, part = scene.type_of(obj), member.removeprefix(f"{obj}-")
    if f"(cangraspfrom {obj} {member} {palm} {f2} {f1})" in _truth(scene_name, domain):
        poses = [
            grasp_candidates(t, GraspSymbols(obj, part, palm, a, b), np.eye(4), prefer_x=_X)
            for a, b in ((f1, f2), (f2, f1))
        ]
        if all(any(np.allclose(g.tcp, h.tcp) for h in poses[1]) for g in poses[0]):
            return "finger order"
    if palm not in PALM_PARTS:
        return "side grasp"
    refusal = pick_refusal(t, part, palm, f1, f2, domain == "utamp2x")
    return "facts" if refusal is None else refusal.rule


@functools.lru_cache(maxsize=64)
def _truth(scene_name: str, domain: str) -> frozenset[str]:
    """`truth_atoms` of a scene, once per scene (a report asks for it per forbidden pick)."""
    return truth_atoms(resolve_scene(scene_name), domain)


def sample_split(
    split: str, n_pairs: int, seed: int, max_steps: int, domain: str = "utamp2"
) -> list[Pair]:
    """`n_pairs` pairs from physics episodes on one split (see the module docstring)."""
    env = UTampKitchenEnv(
        split=split,
        objects=procedural.OBJECT_NAMES,
        masks="geometric",
        record_timings=False,
    )
    model = OutcomeModel(env.universe, domain)
    rng = np.random.default_rng(seed)
    pairs: list[Pair] = []
    try:
        for info in episodes(env, model, seed):
            if len(pairs) >= n_pairs:
                break
            families = _families(env.scene.name)
            tainted = False
            failed: set[int] = set()  # actions that failed in the current state
            for step in range(max_steps):
                i = draw_action(info, model, rng, skip=failed)
                if i is None:
                    break
                reason = model.affordance_failure(i)
                kind, obj, target = env.universe.roles[i]
                before = symbolic_supports(env) if reason is not None else None
                start = time.perf_counter()
                _, _, terminated, _, info = env.step(i)
                macro = info["macro_result"]
                pairs.append(
                    Pair(
                        split=split,
                        scene=env.scene.name,
                        step=step,
                        action=env.action_strings[i],
                        kind=kind,
                        family=families.get(obj, "?"),
                        support_family=families.get(target, "") if kind == "place-support" else "",
                        allowed=reason is None,
                        rules_reason=reason or "",
                        physics=bool(macro["success"]),
                        physics_reason=macro["reason"] or "",
                        step_s=time.perf_counter() - start,
                        after_forbidden=tainted,
                    )
                )
                # a forbidden action that changed the state (carried out, or an object it
                # let fall) leaves a state the rules never lead to
                tainted = tainted or (reason is not None and symbolic_supports(env) != before)
                # a failure leaves the state as it was: the same action from it is the same
                # pair, not a new one (it was once drawn six times in a row)
                if macro["success"]:
                    failed.clear()
                else:
                    failed.add(i)
                print(
                    f"{len(pairs):4d} {split:15s} {env.scene.name:32s} "
                    f"{'allow ' if pairs[-1].allowed else 'forbid'} -> "
                    f"{'ok  ' if macro['success'] else 'fail'} {env.action_strings[i]}",
                    flush=True,
                )
                if len(pairs) >= n_pairs or terminated:
                    break
                if not consistent(env):  # the symbolic state no longer describes physics
                    break
    finally:
        env.close()
    return pairs


def _rate(ok: int, n: int) -> str:
    return f"{ok}/{n} ({ok / n:.1%})" if n else "–"


def summarize(pairs: list[Pair], domain: str = "utamp2") -> dict[str, Any]:
    by_family: dict[str, Counter[str]] = defaultdict(Counter)
    by_support: dict[str, Counter[str]] = defaultdict(Counter)
    for p in pairs:
        key = "allowed" if p.allowed else "forbidden"
        for table, fam in ((by_family, p.family), (by_support, p.support_family)):
            if fam:
                table[fam][f"{key}"] += 1
                table[fam][f"{key}_ok"] += p.physics
                if p.allowed and not p.after_forbidden:
                    table[fam]["allowed_clean"] += 1
                    table[fam]["allowed_clean_ok"] += p.physics
    allowed = [p for p in pairs if p.allowed]
    failures = Counter(
        f"{p.kind} {p.family}"
        + (f" on {p.support_family}" if p.support_family else "")
        + f": {_physics_class(p.physics_reason)}"
        for p in allowed
        if not p.physics
    )
    examples = {}
    for p in allowed:
        if not p.physics:
            examples.setdefault(p.family, []).append(
                {
                    "scene": p.scene,
                    "action": p.action,
                    "reason": p.physics_reason,
                    "after_forbidden": p.after_forbidden,
                }
            )
    clean = [p for p in allowed if not p.after_forbidden]
    picks: dict[str, Counter[str]] = defaultdict(Counter)
    for p in pairs:
        if p.kind == "pick-support" and not p.allowed:
            kind = pick_refusal_kind(p.scene, p.action, p.rules_reason, domain)
            picks[kind]["forbidden"] += 1
            picks[kind]["forbidden_ok"] += p.physics
    return {
        "pairs": len(pairs),
        "allowed": len(allowed),
        "allowed_physics_ok": sum(p.physics for p in allowed),
        "allowed_clean": len(clean),
        "allowed_clean_physics_ok": sum(p.physics for p in clean),
        "forbidden": len(pairs) - len(allowed),
        "forbidden_physics_ok": sum(p.physics for p in pairs if not p.allowed),
        "forbidden_picks": sum(c["forbidden"] for c in picks.values()),
        "forbidden_picks_physics_ok": sum(c["forbidden_ok"] for c in picks.values()),
        # the grasps the rules refuse under every name: a pick named in the other finger
        # order of a grasp they grant is the same grasp (`pick_refusal_kind`)
        "forbidden_grasps": sum(c["forbidden"] for k, c in picks.items() if k != "finger order"),
        "forbidden_grasps_physics_ok": sum(
            c["forbidden_ok"] for k, c in picks.items() if k != "finger order"
        ),
        "forbidden_picks_by_refusal": {
            k: dict(c) for k, c in sorted(picks.items(), key=lambda kc: -kc[1]["forbidden_ok"])
        },
        "by_family": {f: dict(c) for f, c in sorted(by_family.items())},
        "by_support_family": {f: dict(c) for f, c in sorted(by_support.items())},
        "allowed_failures": dict(failures.most_common()),
        "failure_examples": examples,
        "median_step_s": float(np.median([p.step_s for p in pairs])) if pairs else None,
    }


def to_markdown(summary: dict[str, Any], args: argparse.Namespace, wall_s: float) -> str:
    s = summary
    out = [
        "<!-- written by benchmarks/procedural_outcomes.py; do not edit -->",
        "",
        f"`python benchmarks/procedural_outcomes.py --pairs {args.pairs} --splits "
        f"{args.splits} --seed {args.seed} --max-steps {args.max_steps}"
        f"{'' if args.domain == 'utamp2' else ' --domain ' + args.domain}`: {s['pairs']} "
        f"(state, action) pairs in physics, {wall_s / 60:.1f} min wall with "
        f"{args.workers} workers (shared 2-core machine).",
        "",
        f"**Physics succeeded on {_rate(s['allowed_physics_ok'], s['allowed'])} of the actions "
        f"the rules allow**, and on {_rate(s['forbidden_physics_ok'], s['forbidden'])} of those "
        "they forbid; "
        f"of the picks they forbid, physics carried out "
        f"{_rate(s['forbidden_picks_physics_ok'], s['forbidden_picks'])} (target ≤ "
        f"{FORBIDDEN_PICKS:.0%}); of the grasps they refuse under every name (leaving out "
        "the picks named in the other finger order of a grasp they grant: the same grasp), "
        f"{_rate(s['forbidden_grasps_physics_ok'], s['forbidden_grasps'])}.",
        "",
        "An episode ends when the simulation no longer matches the symbolic state, after a "
        "failure or after an action physics carried out otherwise than its effects say (an "
        "object that ended inside its support, not on it): the rules judge the symbolic "
        "state, and a state it misdescribes is not one to judge them on. An action that "
        "failed is not drawn again until the state changes: from the same state it is the "
        "same pair. "
        "The last column but one counts only the allowed actions taken in states reached with "
        "the rules' consent; the others follow an action the rules forbid that changed the "
        "state anyway (physics carried it out as its effects say, or it let an object fall "
        "beside another). In the states reached with the "
        f"rules' consent physics succeeded on "
        f"{_rate(s['allowed_clean_physics_ok'], s['allowed_clean'])} of the allowed actions.",
        "",
        "| family (object acted on) | rules allow: physics succeeds | "
        f"≥ {TARGET:.0%} | rules allow, no forbidden action before | ≥ {TARGET:.0%} | "
        "rules forbid: physics succeeds |",
        "|---|---|---|---|---|---|",
    ]
    below: dict[str, list[str]] = {"": [], "_clean": []}
    for fam, c in s["by_family"].items():
        cells = []
        for key in below:
            n, ok = c.get(f"allowed{key}", 0), c.get(f"allowed{key}_ok", 0)
            meets = "–" if not n else ("yes" if ok >= TARGET * n else "**no**")
            if n and ok < TARGET * n:
                below[key].append(fam)
            cells += [_rate(ok, n), meets]
        out.append(
            f"| {fam} | {' | '.join(cells)} | "
            f"{_rate(c.get('forbidden_ok', 0), c.get('forbidden', 0))} |"
        )
    out += [
        "",
        f"Families below {TARGET:.0%} where the rules allow: "
        + (", ".join(below[""]) if below[""] else "none")
        + "; in states reached with the rules' consent: "
        + (", ".join(below["_clean"]) if below["_clean"] else "none")
        + ".",
    ]
    out += [
        "",
        "| family (support of a placement) | rules allow: physics succeeds | rules forbid: "
        "physics succeeds |",
        "|---|---|---|",
    ]
    for fam, c in s["by_support_family"].items():
        out.append(
            f"| {fam} | {_rate(c.get('allowed_ok', 0), c.get('allowed', 0))} | "
            f"{_rate(c.get('forbidden_ok', 0), c.get('forbidden', 0))} |"
        )
    out += [
        "",
        "Picks the rules forbid, by the rule that refuses them (`finger order`: the grasp is "
        "granted under its other finger order, which gives the same grasp poses: the hand "
        "tries both finger-axis signs and the measured grasp is named in the canonical order; "
        "`side grasp`: the palm on a side part, a horizontal approach; the rules grant the "
        "palm on the part facing up only; `facts`: the rules refuse none of its parts, "
        "`object_facts` leaves it out):",
        "",
        "| refused by | picks | physics succeeds |",
        "|---|---|---|",
    ]
    for kind, c in s["forbidden_picks_by_refusal"].items():
        out.append(f"| {kind} | {c['forbidden']} | {_rate(c['forbidden_ok'], c['forbidden'])} |")
    out += ["", "Allowed actions physics failed, by kind:", ""]
    if not s["allowed_failures"]:
        out.append("none")
    out += [f"* {k}: {n}" for k, n in s["allowed_failures"].items()]
    out += ["", "Each of them, with the simulator's reason:", ""]
    for fam, examples in sorted(s["failure_examples"].items()):
        out += [
            f"* {fam}: `{e['scene']}` `{e['action']}`"
            + (" (after a forbidden action)" if e.get("after_forbidden") else "")
            + f": {e['reason']}"
            for e in examples
        ]
    return "\n".join(out) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=1200, help="pairs in all (split by split)")
    ap.add_argument("--splits", default="train,test-families")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-steps", type=int, default=12)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="docs/results/procedural_outcomes")
    ap.add_argument(
        "--domain",
        default="utamp2",
        choices=("utamp2", "utamp2x"),
        help="whose rules judge (utamp2x: with the extended grasps)",
    )
    ap.add_argument("--from-json", action="store_true", help="re-summarize <out>.json")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    out = Path(args.out)
    splits = [s.strip() for s in args.splits.split(",") if s.strip()]
    start = time.perf_counter()
    sampled: dict[str, str] = {}  # the run that drew the pairs, when re-summarized
    if args.from_json:
        old = json.loads(out.with_suffix(".json").read_text())
        sampled = old.get("sampled") or {"command": old["command"], "commit": old["commit"]}
        names = {f.name for f in fields(Pair)}
        pairs = [Pair(**{k: v for k, v in p.items() if k in names}) for p in old["all_pairs"]]
        wall = float(old["wall_time_s"])
        for key in ("pairs", "splits", "seed", "max_steps", "workers"):  # as measured
            setattr(args, key, old["args"][key])
        args.domain = old["args"].get("domain", "utamp2")
    else:
        # each worker samples its share of one split from its own seed
        jobs = []
        per_worker = max(1, args.workers // len(splits)) if args.workers >= len(splits) else 1
        for k, split in enumerate(splits):
            share = args.pairs // len(splits) + (k < args.pairs % len(splits))
            for w in range(per_worker):
                n = share // per_worker + (w < share % per_worker)
                jobs.append((split, n, args.seed + 1000 * k + w, args.max_steps, args.domain))
        with ProcessPoolExecutor(args.workers) as pool:
            parts = list(pool.map(sample_split, *zip(*jobs, strict=True)))
        pairs = [p for part in parts for p in part]
        wall = time.perf_counter() - start
    summary = summarize(pairs, args.domain)
    data = {
        **summary,
        **({"sampled": sampled} if sampled else {}),
        "args": vars(args),
        "wall_time_s": wall,
        "all_pairs": [asdict(p) for p in pairs],
    }
    text = to_markdown(summary, args, wall)
    if sampled:
        text += (
            f"\nThe pairs were drawn by `{sampled['command']}` at commit "
            f"`{sampled['commit']}`; this page summarizes them again (`--from-json`).\n"
        )
    write_results(out.parent, out.name, data, text, indent=1)
    print(text)


if __name__ == "__main__":
    main()
