"""How well the symbolic outcome model stands in for physics (geometric masks, both suites).

    python benchmarks/outcome_model.py [--pairs 600] [--seed 0] [--max-steps 12]
        [--out docs/results/outcome_model] [--from-json]

Sampling: episodes in the physics env (``masks="geometric"``, MuJoCo backend) on scenes
drawn by the env's RNG. At every step the action is drawn among the mask-allowed ones,
from those the outcome model predicts to succeed with probability 1/2 and otherwise from
those it predicts to fail (so both outcomes occur); the model's verdict (ground-truth
U-TAMP-2 precondition) is recorded, then the simulator executes the action. An episode ends
at the goal, after `--max-steps` steps, or when the simulation no longer matches the symbolic
state (after a physical failure that moved something: a dropped or pushed object), so every
pair starts from a state both sides agree on. Pairs are split evenly between the suites.

Reported: agreement (prediction == physical outcome), the confusion matrix, and the
disagreements grouped by kind, e.g. "physics succeeded where ground truth forbids:
canGraspFrom salt by its body, palm on a side". Writes ``<out>.json`` (every pair) and
``<out>.md``. A long physics run: run it ``nice``d.
"""

from __future__ import annotations

import argparse
import json
import re
import time
from collections import Counter
from collections.abc import Collection, Iterator
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
from _common import write_results  # benchmarks/ is on sys.path when run as a script

from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.provenance import commit
from utamp_gym.suites import resolve_scene
from utamp_gym.symbolic.outcome import OutcomeModel, truth_atoms

SUITES = ("pick-place", "sliding")
_NUMBER = re.compile(r"-?\d+(\.\d+)?")


@dataclass(frozen=True)
class Pair:
    """One (state, action) pair: the model's prediction and what physics did."""

    suite: str
    scene: str
    step: int
    action: str
    predicted: bool
    predicted_reason: str
    physics: bool
    physics_reason: str
    step_s: float

    @property
    def kind(self) -> str:
        return disagreement_kind(self) if self.predicted != self.physics else "agree"


def describe_affordance(reason: str, truth: frozenset[str] = frozenset()) -> str:
    """A short class of a false ground-truth literal, e.g. ``canGraspFrom salt by its body,
    palm on a side`` (from ``canGraspFrom(salt, salt-body, left, back, front) is false``);
    `truth` (the scene's ground-truth atoms) tells a grasp whose fingers are only swapped."""
    text = reason.removesuffix(" is false (ground truth)")
    negated = text.startswith("not ")
    pred, _, rest = text.removeprefix("not ").partition("(")
    args = [a.strip() for a in rest.rstrip(")").split(",")]
    if pred == "canGraspFrom":
        obj, member, palm = args[0], args[1].removeprefix(f"{args[0]}-"), args[2]
        swapped = f"(cangraspfrom {args[0]} {args[1]} {palm} {args[4]} {args[3]})"
        if swapped in truth:
            return f"canGraspFrom {obj} by its {member}, a ground-truth grasp with fingers swapped"
        where = "top or bottom" if palm in ("on", "under") else "a side"
        return f"canGraspFrom {obj} by its {member}, palm on {where}"
    if pred == "canLift":
        return f"{'not ' if negated else ''}canLift {args[0]}"
    if pred == "isSupportive":
        return f"isSupportive {args[0]} '{args[1]}'"
    if pred == "isP2PSupportive":
        return f"isP2PSupportive {args[3]} on {args[1]}"
    return f"{pred} {' '.join(args[:2])}"


def family(kind: str) -> str:
    """The coarse class of a disagreement kind: its direction and false affordance."""
    if kind.startswith("physics failed"):
        return "physics failed where ground truth allows"
    why = kind[kind.index("(") + 1 : -1]
    if "fingers swapped" in why:
        return "succeeded: a ground-truth grasp with the fingers swapped"
    return f"succeeded: {why.split()[0]} false"


def _physics_class(reason: str) -> str:
    """A physics failure reason without numbers and details: its kind."""
    head = reason.split(" (", 1)[0].split(": ", 1)[0]
    return _NUMBER.sub("#", head).strip()


def disagreement_kind(p: Pair) -> str:
    name, obj = p.action.strip("()").split()[:2]
    if not p.predicted:
        why = describe_affordance(p.predicted_reason, truth_atoms(resolve_scene(p.scene)))
        return f"physics succeeded where ground truth forbids: {name} {obj} ({why})"
    why = _physics_class(p.physics_reason)
    return f"physics failed where ground truth allows: {name} {obj} ({why})"


def symbolic_supports(env: UTampKitchenEnv) -> dict[str, str | None]:
    """Object -> what it rests on in the symbolic state (None: held)."""
    scene = env.scene
    objects = set(scene.object_names)
    places = objects | {s.name for s in scene.slots}
    up = {
        a[1:-1].split()[1]: a[1:-1].split()[2] for a in env.static_atoms if a.startswith("(force ")
    }
    out: dict[str, str | None] = {}
    for atom in env.true_atoms():
        parts = atom[1:-1].split()
        if parts[0] != "oc" or len(parts) != 4:
            continue
        _, part, x, y = parts
        if x == "hand" and y in objects:
            out[y] = None
        elif x in places and y in objects and up.get(x) == part:
            out[y] = x
    return out


def consistent(env: UTampKitchenEnv) -> bool:
    """Whether the simulation matches the symbolic state: the same support for every object
    (resting on top of it, not inside), one object on each support (the domain's ``oc`` holds
    one: a tumbler that fell off another into a third's mouth "rested" on the same support as
    the third, `procedural-v1/train/0095`), and the same object in the hand."""
    backend = env.backend
    assert backend is not None
    physical = backend.physical_state()
    places = set(env.scene.object_names) | {slot.name for slot in env.scene.slots}
    carried = [s for s in physical.supports.values() if s in places]
    if len(carried) != len(set(carried)):
        return False
    mine = symbolic_supports(env)
    held = physical.held.obj if physical.held is not None else None
    for obj in env.scene.object_names:
        want = mine.get(obj, "?")
        got = None if obj == held else physical.supports.get(obj)
        if want != got or (got is not None and not physical.on_top.get(obj, False)):
            return False
    return True


def draw_action(
    info: dict[str, Any],
    model: OutcomeModel,
    rng: np.random.Generator,
    skip: Collection[int] = (),
) -> int | None:
    """An action the env's mask allows (less `skip`), from those the outcome model predicts
    to succeed with probability 1/2 (always when all do) and otherwise from the others;
    None when the mask allows none. The walks of this module and `procedural_outcomes`."""
    allowed = np.flatnonzero(info["action_mask"])
    allowed = allowed[~np.isin(allowed, sorted(skip))]
    if not allowed.size:
        return None
    ok = model.affordances_hold()[allowed]
    pool = allowed[ok] if ok.any() and (rng.random() < 0.5 or ok.all()) else allowed[~ok]
    return int(rng.choice(pool))


def episodes(env: UTampKitchenEnv, model: OutcomeModel, seed: int) -> Iterator[dict[str, Any]]:
    """Episode after episode of `env` (reset with `seed` the first time, then drawing on),
    the outcome model reset with it: the reset's info. The walks of this module and
    `procedural_outcomes`."""
    first = True
    while True:
        _, info = env.reset(seed=seed if first else None)
        first = False
        model.reset(env.scene)
        yield info


def sample_suite(suite: str, n_pairs: int, seed: int, max_steps: int) -> list[Pair]:
    """`n_pairs` pairs from episodes of one suite (see the module docstring)."""
    env = UTampKitchenEnv(suite=suite, masks="geometric", record_timings=False)
    model = OutcomeModel(env.universe)
    rng = np.random.default_rng(seed)
    pairs: list[Pair] = []
    try:
        for info in episodes(env, model, seed):
            if len(pairs) >= n_pairs:
                break
            for step in range(max_steps):
                i = draw_action(info, model, rng)
                if i is None:
                    break
                predicted_reason = model.affordance_failure(i)
                start = time.perf_counter()
                _, _, terminated, _, info = env.step(i)
                macro = info["macro_result"]  # the MacroResult's fields
                pairs.append(
                    Pair(
                        suite=suite,
                        scene=env.scene.name,
                        step=step,
                        action=env.action_strings[i],
                        predicted=predicted_reason is None,
                        predicted_reason=predicted_reason or "",
                        physics=bool(macro["success"]),
                        physics_reason=macro["reason"] or "",
                        step_s=time.perf_counter() - start,
                    )
                )
                print(
                    f"{len(pairs):4d} {suite:10s} {env.scene.name:16s} "
                    f"{'ok  ' if pairs[-1].predicted else 'fail'} -> "
                    f"{'ok  ' if macro['success'] else 'fail'} {env.action_strings[i]}",
                    flush=True,
                )
                if len(pairs) >= n_pairs or terminated:
                    break
                if not macro["success"] and not consistent(env):
                    break  # the simulator moved away from the symbolic state
    finally:
        env.close()
    return pairs


def summarize(pairs: list[Pair]) -> dict[str, Any]:
    agree = sum(p.predicted == p.physics for p in pairs)
    confusion = Counter(
        (("ok" if p.predicted else "fail"), ("ok" if p.physics else "fail")) for p in pairs
    )
    kinds = Counter(p.kind for p in pairs if p.kind != "agree")
    families = Counter(family(k) for k in kinds.elements())
    examples = {}
    for p in pairs:
        if p.kind != "agree":
            examples.setdefault(p.kind, p)
    per_suite = {
        s: {
            "pairs": len(g),
            "agreement": sum(p.predicted == p.physics for p in g) / len(g) if g else None,
        }
        for s in SUITES
        if (g := [p for p in pairs if p.suite == s])
    }
    return {
        "pairs": len(pairs),
        "agreement": agree / len(pairs) if pairs else None,
        "per_suite": per_suite,
        "confusion": {f"model {a}, physics {b}": n for (a, b), n in sorted(confusion.items())},
        "by_family": dict(families.most_common()),
        "disagreements": [
            {
                "kind": k,
                "count": n,
                "example": examples[k].action,
                "physics_reason": examples[k].physics_reason,
                "model_reason": examples[k].predicted_reason,
            }
            for k, n in kinds.most_common()
        ],
        "median_step_s": float(np.median([p.step_s for p in pairs])) if pairs else None,
    }


def to_markdown(summary: dict[str, Any], args: argparse.Namespace, wall_s: float) -> str:
    out = [
        "# Outcome model against physics (geometric masks)",
        "",
        f"`python benchmarks/outcome_model.py --pairs {args.pairs} --seed {args.seed} "
        f"--max-steps {args.max_steps}`: {summary['pairs']} (state, action) pairs, "
        f"{wall_s / 60:.1f} min wall (shared 2-core machine; median macro step "
        f"{summary['median_step_s']:.2f} s).",
        "",
        f"**Agreement: {summary['agreement']:.1%}** "
        + ", ".join(
            f"{s} {d['agreement']:.1%} of {d['pairs']}" for s, d in summary["per_suite"].items()
        ),
        "",
        "| outcome model | physics | pairs |",
        "|---|---|---|",
    ]
    for key, n in summary["confusion"].items():
        model, physics = key.split(", ")
        out.append(f"| {model.removeprefix('model ')} | {physics.removeprefix('physics ')} | {n} |")
    out += ["", "## Disagreements by class", "", "| class | pairs |", "|---|---|"]
    out += [f"| {k} | {n} |" for k, n in summary["by_family"].items()]
    out += ["", "## Disagreements by kind", "", "| kind | pairs | example action | physics |"]
    out.append("|---|---|---|---|")
    for d in summary["disagreements"]:
        out.append(
            f"| {d['kind']} | {d['count']} | `{d['example']}` | "
            f"{d['physics_reason'] or 'success'} |"
        )
    return "\n".join(out) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=600, help="pairs in all (split by suite)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-steps", type=int, default=12, help="steps per episode at most")
    ap.add_argument("--out", default="docs/results/outcome_model")
    ap.add_argument(
        "--from-json", action="store_true", help="re-summarize the pairs of <out>.json, no physics"
    )
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    out = Path(args.out)
    start = time.perf_counter()
    pairs: list[Pair] = []
    if args.from_json:
        old = json.loads(out.with_suffix(".json").read_text())
        names = {f.name for f in fields(Pair)}
        pairs = [Pair(**{k: v for k, v in p.items() if k in names}) for p in old["all_pairs"]]
        wall = float(old["wall_time_s"])
        args.pairs, args.seed, args.max_steps = (
            old["args"][k] for k in ("pairs", "seed", "max_steps")
        )
    else:
        for k, suite in enumerate(SUITES):
            share = args.pairs // len(SUITES) + (k < args.pairs % len(SUITES))
            pairs += sample_suite(suite, share, args.seed + k, args.max_steps)
        wall = time.perf_counter() - start
    summary = summarize(pairs)
    data = {
        **summary,
        "args": vars(args),
        "wall_time_s": wall,
        "all_pairs": [{**asdict(p), "kind": p.kind} for p in pairs],
    }
    text = to_markdown(summary, args, wall)
    write_results(out.parent, out.name, data, text, indent=1)
    print(text)


if __name__ == "__main__":
    main()
