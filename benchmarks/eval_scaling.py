"""The same physics sweep with the local executor and with Ray, measured in one run.

Runs one `utamp eval` sweep (default: pick-place, utamp2-gt, the runs of shard 1/5 — about
20 scenes spread over every object count — seed 0) into fresh folders twice: with the
local executor (`--workers` processes) and with Ray on a local instance with as many
CPUs. Ray's instance is started before and stopped after its sweep, and its start-up is
reported apart: a cluster is started once (`ray start --head`) and serves many sweeps.
Prints both wall times, the overhead ratio ray / local (target <= 1.15), the ratio with
Ray's start-up included, whether the rows agree (wall-clock columns excepted), and the
load average, since a busy machine distorts every figure. With ``--rounds N`` the two
executors alternate N times and the medians are compared.

    python benchmarks/eval_scaling.py [--suite pick-place] [--methods utamp2-gt]
        [--shard 1/5] [--scenes GLOB] [--seeds 1] [--workers 2] [--rounds 1] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from utamp_gym.distributed import LocalExecutor, RayExecutor, import_ray
from utamp_gym.eval.sweep import SweepConfig, parse_shard, run_sweep

TARGET_RATIO = 1.15


def _local(cfg: SweepConfig, out: Path, workers: int) -> dict[str, Any]:
    start = time.perf_counter()
    report = run_sweep(cfg, out, executor=LocalExecutor(workers), progress=False)
    return {"wall_s": time.perf_counter() - start, "rows": report.rows}


def _ray(cfg: SweepConfig, out: Path, workers: int) -> dict[str, Any]:
    ray = import_ray()
    start = time.perf_counter()
    ray.init(
        address="local",
        num_cpus=workers,
        include_dashboard=False,
        log_to_driver=False,
        logging_level="warning",
    )
    started = time.perf_counter()
    try:
        report = run_sweep(cfg, out, executor=RayExecutor(), progress=False)
        swept = time.perf_counter()
    finally:
        ray.shutdown()
    return {
        "wall_s": swept - started,
        "start_s": started - start,
        "total_s": time.perf_counter() - start,
        "rows": report.rows,
    }


def _same_rows(a: list[Any], b: list[Any]) -> bool:
    return {r.key: r.outcome() for r in a} == {r.key: r.outcome() for r in b}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="pick-place")
    ap.add_argument("--methods", default="utamp2-gt", help="comma-separated")
    ap.add_argument("--shard", default="1/5", help="the part of the suite's runs to sweep")
    ap.add_argument("--scenes", help="glob over scene names (instead of all of the suite)")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2, help="local processes = Ray CPUs")
    ap.add_argument("--rounds", type=int, default=1, help="alternate the executors N times")
    ap.add_argument("--json", help="also write the measurements here")
    args = ap.parse_args()
    cfg = SweepConfig(
        args.suite,
        tuple(m.strip() for m in args.methods.split(",")),
        seeds=args.seeds,
        scenes=args.scenes,
        shard=parse_shard(args.shard) if args.shard else None,
    )
    load_before = os.getloadavg()
    local, ray = [], []
    with tempfile.TemporaryDirectory(prefix="utamp_scaling_") as tmp:
        for i in range(args.rounds):
            local.append(_local(cfg, Path(tmp) / f"local{i}", args.workers))
            ray.append(_ray(cfg, Path(tmp) / f"ray{i}", args.workers))
    load_after = os.getloadavg()
    runs = len(local[0]["rows"])
    same = all(_same_rows(local[0]["rows"], r["rows"]) for r in [*local, *ray])
    t_local = statistics.median(r["wall_s"] for r in local)
    t_ray = statistics.median(r["wall_s"] for r in ray)
    t_start = statistics.median(r["start_s"] for r in ray)
    t_total = statistics.median(r["total_s"] for r in ray)
    ratio, ratio_total = t_ray / t_local, t_total / t_local
    print(
        f"sweep: {cfg.suite}, {', '.join(cfg.methods)}, shard {args.shard}, "
        f"{args.seeds} seed(s): {runs} physics runs, {args.workers} workers/CPUs, "
        f"{args.rounds} round(s) (medians)"
    )
    print(f"local executor ({args.workers} processes): {t_local:7.1f} s")
    print(f"ray executor (local instance, {args.workers} CPUs): {t_ray:7.1f} s")
    print(f"ray instance start-up: {t_start:.1f} s; with start-up and shutdown {t_total:.1f} s")
    verdict = "within" if ratio <= TARGET_RATIO else "OVER"
    print(f"overhead ratio ray / local: {ratio:.3f} ({verdict} the {TARGET_RATIO} target)")
    print(f"ratio with Ray's start-up included: {ratio_total:.3f}")
    print(f"rows identical (wall-clock columns excepted): {'yes' if same else 'NO'}")
    print(f"load average before {load_before}, after {load_after} (2 cores)")
    if args.json:
        out = {
            "runs": runs,
            "workers": args.workers,
            "rounds": args.rounds,
            "local_wall_s": [round(r["wall_s"], 2) for r in local],
            "ray_wall_s": [round(r["wall_s"], 2) for r in ray],
            "ray_start_s": [round(r["start_s"], 2) for r in ray],
            "ray_total_s": [round(r["total_s"], 2) for r in ray],
            "ratio": round(ratio, 3),
            "ratio_with_start": round(ratio_total, 3),
            "rows_identical": same,
            "load_average_before": load_before,
            "load_average_after": load_after,
        }
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
