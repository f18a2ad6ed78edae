"""Learning per env step of `utamp train`'s object-centric default, against the measured row.

Why: `benchmarks/train_speed.py` shows the default configuration trains faster per wall
second; this checks that it learns at least as much per env step. It trains the MaskablePPO
slot policy as the generalisation table does (`benchmarks/agents.py`: UTampKitchenProcedural-v0,
objects interface, geometric masks, 8 envs, 24,576 steps, 30 evaluation episodes every
4,096 steps) with this tree's default settings, one run per seed, evaluates each final model
on every scene of ``procedural-v1/train`` (symbolic grounding, seed 0, as the table does),
and sets the mean and 95 % t interval over seeds beside the table's row
(``docs/results/agents.json``, "MaskablePPO, slot transformer").

Writes ``<out>.md`` and ``<out>.json``.

    python benchmarks/train_speed_learning.py [--seeds 3] [--steps 24576] [--workers 0]
        [--hyperparams JSON] [--runs runs/train_speed_learning]
        [--out docs/results/train_speed_learning] [--rewrite]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from agents import evaluate  # noqa: E402

from utamp_gym.eval.intervals import t_interval  # noqa: E402
from utamp_gym.provenance import provenance, write_json, write_markdown  # noqa: E402

ROW = "MaskablePPO, slot transformer"
SUITE = "procedural-v1/train"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check the command a results file recorded)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=24_576)
    ap.add_argument("--eval-every", type=int, default=4_096)
    ap.add_argument("--workers", type=int, default=0, help="evaluation worker processes")
    ap.add_argument("--hyperparams", default="{}", help="JSON overrides of the defaults")
    ap.add_argument("--runs", default="runs/train_speed_learning")
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "train_speed_learning"))
    ap.add_argument("--rewrite", action="store_true", help="only rewrite <out>.md from <out>.json")
    return ap


def main() -> None:
    args = build_parser().parse_args()
    if args.rewrite:
        write(json.loads(Path(args.out).with_suffix(".json").read_text()), Path(args.out))
        return

    from utamp_gym.rl.config import default_hyperparams
    from utamp_gym.rl.train import train

    hyper = json.loads(args.hyperparams)
    runs = Path(args.runs)
    prov = provenance()  # the code as it is when the run starts
    load0 = os.getloadavg()[0]
    per_seed = []
    for seed in range(args.seeds):
        t0 = time.perf_counter()
        result = train(
            env_id="UTampKitchenProcedural-v0", masks="geometric", interface="objects",
            steps=args.steps, n_envs=8, seed=seed, out=runs / f"seed_{seed}",
            eval_every=args.eval_every, eval_episodes=30, progress=False, hyperparams=hyper,
        )  # fmt: skip
        wall = time.perf_counter() - t0
        rows = evaluate(f"rl:{result.model_path}", SUITE, runs / "eval" / f"seed_{seed}",
                        args.workers)  # fmt: skip
        rate = sum(r.success for r in rows) / len(rows)
        per_seed.append({"seed": seed, "steps": result.steps, "success": rate, "n": len(rows),
                         "train_time_s": result.train_time_s, "wall_time_s": round(wall, 1),
                         "curve": result.curve})  # fmt: skip
        print(f"seed {seed}: success {rate:.3f} on {SUITE} after {result.steps} steps "
              f"(training {result.train_time_s:.0f} s)", flush=True)  # fmt: skip
    data = {
        **prov, "steps": args.steps,
        "settings": {**default_hyperparams("maskable-ppo", 8, "objects"), **hyper},
        "per_seed": per_seed, "load": [load0, os.getloadavg()[0]],
    }  # fmt: skip
    write(data, Path(args.out))


def write(data: dict[str, Any], out: Path) -> None:
    """``<out>.json`` (the runs, the table's row beside them) and ``<out>.md`` (the table)."""
    old = json.loads((ROOT / "docs" / "results" / "agents.json").read_text())["methods"][ROW]
    old_rates = [s["success"]["train"]["rate"] for s in old["per_seed"]]
    old_mean, old_half = t_interval(old_rates)
    per_seed, settings = data["per_seed"], data["settings"]
    mean, half = t_interval([s["success"] for s in per_seed])
    data = {**data, "mean": mean, "half_width": half,
            "row": {"rates": old_rates, "mean": old_mean, "half_width": old_half}}  # fmt: skip
    width = settings["policy_kwargs"].get("features_extractor_kwargs", {}).get("d_model", 64)
    verdict = "within or above" if mean >= old_mean - old_half else "below"
    text = "\n".join([
        f"| policy | seeds | success on `{SUITE}` (mean ± 95 % t) | per seed | env steps "
        "| training s per seed |",
        "|---|---|---|---|---|---|",
        f"| the generalisation table's row (`docs/results/agents.json`; width 64) "
        f"| {len(old_rates)} | {old_mean:.2f} ± {old_half:.2f} "
        f"| {' / '.join(f'{r:.2f}' for r in old_rates)} | {old['per_seed'][0]['steps']:,} "
        f"| {' / '.join(str(round(s['train_time_s'])) for s in old['per_seed'])} |",
        f"| slot policy width {width}, {settings['n_epochs']} epochs (`{data['commit']}`) "
        f"| {len(per_seed)} | {mean:.2f} ± {half:.2f} "
        f"| {' / '.join(format(s['success'], '.2f') for s in per_seed)} | {data['steps']:,} "
        f"| {' / '.join(str(round(s['train_time_s'])) for s in per_seed)} |",
        "",
        f"The mean is {verdict} the row's interval. Settings: "
        f"`{json.dumps(settings['policy_kwargs'])}`, n_epochs {settings['n_epochs']}, batch "
        f"{settings['batch_size']}, n_steps {settings['n_steps']} x 8 envs. Command: "
        f"`{data['command']}`; shared 2-core machine, load {data['load'][0]:.1f} at the start "
        f"and {data['load'][1]:.1f} at the end (training times are indicative only). "
        "Generated by `benchmarks/train_speed_learning.py`.",
    ]) + "\n"  # fmt: skip
    print(text)
    write_markdown(out.with_suffix(".md"), text, data)
    write_json(out.with_suffix(".json"), data, indent=1, default=str)


if __name__ == "__main__":
    main()
