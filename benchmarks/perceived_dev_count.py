"""`utamp2-perceived` on six-object development scenes: the figures the perceiver and the
open loop's hoping were developed against besides procedural-v1/train
(docs/results/perceived-dev-count.{md,json}).

procedural-v1/train has two to five objects a scene; test-count has six. These scenes are
drawn by the same generator with test-count's recipe (six objects of the training families,
the training instance pool) from seeds no split keeps (`FIRST_SEED` on, where every split's
seeds end below 2400): no scene of any split is read here. Each achievable scene is
perceived with the survey cameras (seed 0) and planned open loop as `utamp eval --methods
utamp2-perceived --grounding symbolic` does, and the plan checked in the declared world; an
invalid plan's false facts are traced to the reading that granted them
(`utamp_gym.methods.blame`, as on the test splits' page).

    python benchmarks/perceived_dev_count.py [--seeds 3200] [--workers 2]
        [--results docs/results]
"""

from __future__ import annotations

import argparse
from multiprocessing import Pool
from pathlib import Path

from _common import write_results  # benchmarks/ is on sys.path when run as a script

from utamp_gym.methods.blame import ORIGINS, blame_plan
from utamp_gym.methods.perceived import perceive_scene, plan_perceived
from utamp_gym.planning.crosscheck import check_against_ground_truth
from utamp_gym.provenance import commit
from utamp_gym.suites.procedural.layout import generate_scene
from utamp_gym.suites.procedural.seeds import split_seeds
from utamp_gym.suites.procedural.spec import SPLITS, NoLayout

ROOT = Path(__file__).resolve().parents[1]
FIRST_SEED = 100_000
RECIPE = "test-count"  # the split whose recipe (families, pool, six objects) is drawn


def scene_row(seed: int) -> dict[str, object] | None:
    """The outcome on the scene of `seed` (None: the seed has no layout)."""
    try:
        generated = generate_scene(RECIPE, seed)
    except NoLayout:
        return None
    scene = generated.scene._replace(name=f"dev-count/{seed}")
    row: dict[str, object] = {"seed": seed, "achievable": generated.achievable}
    outcome, seen = plan_perceived(scene, 0)
    valid = outcome.solved and check_against_ground_truth(scene, outcome.plan).valid
    row.update(solved=bool(outcome.solved), valid=bool(valid), reason=outcome.reason)
    row["doubt"] = "" if seen is None else seen.doubt.note()
    if outcome.solved and not valid:  # the likely readings, as `perceived_procedural` blames
        blamed = blame_plan(scene, perceive_scene(scene, 0), outcome.plan)
        row["blame"] = [f"{f.origin}: {f.fact}" for f in blamed]
    return row


def _markdown(rows: list[dict[str, object]], seeds: range) -> str:
    ach = [r for r in rows if r["achievable"]]
    unach = [r for r in rows if not r["achievable"]]
    ok = sum(bool(r["valid"]) for r in ach)
    no_plan = sum(not r["solved"] for r in ach)
    invalid = sum(bool(r["solved"]) and not r["valid"] for r in ach)
    failed = ", ".join(str(r["seed"]) for r in ach if not r["valid"]) or "none"
    first = [str(r["blame"][0]).split(":")[0] for r in ach if r.get("blame")]
    origins = ", ".join(f"{o} {first.count(o)}" for o in ORIGINS if o in first) or "none"
    return "\n".join([
        f"`utamp2-perceived` open loop on the six-object development scenes: seeds "
        f"{seeds.start}-{seeds.stop - 1} drawn with {RECIPE}'s recipe "
        f"(`benchmarks/perceived_dev_count.py`), {len(rows)} with a layout. No scene of a "
        "split is among them; the test splits were only evaluated.",
        "",
        "| scenes | achievable planned validly | achievable failed: no plan / plan invalid "
        "| unachievable reported unsolvable |",
        "|---|---|---|---|",
        f"| {len(rows)} | {ok}/{len(ach)} = **{ok / max(len(ach), 1):.2f}** | {no_plan} / "
        f"{invalid} | {sum(not r['solved'] for r in unach)}/{len(unach)} |",
        "",
        f"Achievable scenes that failed (seeds): {failed}.",
        "",
        "Invalid plans by where their first false fact came from (`utamp_gym.methods.blame`: "
        f"an alternative hoped for, or one object's likely reading): {origins}.",
        "",
    ])  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=3200, help="seeds tried from FIRST_SEED on")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--results", type=Path, default=ROOT / "docs" / "results")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    seeds = range(FIRST_SEED, FIRST_SEED + args.seeds)
    kept = {s for split in SPLITS for s in split_seeds(split)}
    if kept & set(seeds):
        raise SystemExit(f"seeds {sorted(kept & set(seeds))[:3]}... are a split's")
    if args.workers > 1:
        with Pool(args.workers) as pool:
            found = list(pool.imap(scene_row, seeds))
    else:
        found = [scene_row(s) for s in seeds]
    rows = [r for r in found if r is not None]
    md = _markdown(rows, seeds)
    print(md)
    write_results(args.results, "perceived-dev-count", {"recipe": RECIPE, "rows": rows}, md,
                  indent=1)  # fmt: skip


if __name__ == "__main__":
    main()
