"""Memory over long runs: RSS of a physics env over resets and full episodes, and of a vector env.

Four measurements, each in a fresh Python process so none inherits another's heap:

* ``resets``: one ``UTampKitchen-v0`` env (physics grounding), ``--resets`` resets (seeds
  0, 1, ...): RSS every 100, and the growth per 1,000 resets after the first 500 (least-squares
  slope; target <= 10 MB);
* ``episodes``: the same env, ``--episodes`` full episodes of the planner policy
  (`utamp_gym.agents.PlannerPolicy`, one episode per seed): RSS after each, and the
  growth over the last half (target <= 10 MB over the last 100 of 200), and how many scenes
  they met: the env keeps what a reset derives from each scene it meets (up to
  `utamp_gym.symbolic.scene_cache.SCENES_KEPT`), so its memory grows with the scenes it has met;
* ``repeat``: the same, ``--episodes`` episodes cycling over ``--repeat-scenes`` scenes, so
  every scene is met within the first few: what an episode itself leaves behind. Its growth
  compares two episodes of the same scene (target <= 10 MB over the last 100 of 200);
* ``vector``: a Gymnasium ``AsyncVectorEnv`` of ``--vector-envs`` physics envs, ``--vector-resets``
  resets: the RSS of the parent plus its workers, and its growth over the last half (target
  <= 10 MB over the last 50 of 100).

Writes the figures to ``docs/results/memory.json`` and a table to ``docs/results/memory.md``
(``--out`` changes the folder), which the docs include. Run it nice'd; it takes a while::

    nice -n 10 python benchmarks/memory.py [--resets 2000] [--episodes 200] [--vector-resets 100]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from utamp_gym.provenance import commit, write_json, write_markdown

ROOT = Path(__file__).resolve().parents[1]
ENV_ID = "UTampKitchen-v0"
TARGET_MB = 10.0
MiB = 2**20
PARTS = ("resets", "episodes", "repeat", "vector")  # the measurements, in the table's order


def rss_mb(pid: int | str = "self") -> float:
    """Resident set size of a process in MiB (Linux /proc)."""
    with open(f"/proc/{pid}/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / MiB


# ---------------------------------------------------------------- the measurements (children)
def measure_resets(n: int, every: int = 100) -> list[tuple[int, float]]:
    import gymnasium as gym

    import utamp_gym  # noqa: F401  (registers the env ids)

    env = gym.make(ENV_ID)
    samples = [(0, rss_mb())]
    for i in range(1, n + 1):
        env.reset(seed=i)
        if i % every == 0:
            samples.append((i, rss_mb()))
    env.close()
    return samples


def measure_episodes(n: int, cycle: int = 0) -> tuple[list[tuple[int, float]], dict[str, int]]:
    """RSS after each of `n` planner-policy episodes (seeds 1 .. n); with `cycle`, episode i
    plays scene i % cycle of the first `cycle` distinct scenes the env's seeds give."""
    import gymnasium as gym

    import utamp_gym  # noqa: F401
    from utamp_gym.agents import PlannerPolicy

    env = gym.make(ENV_ID)
    names: list[str] = []
    for seed in range(1, 100 * cycle + 1):
        if len(names) == cycle:
            break
        env.reset(seed=seed)
        if env.unwrapped.scene.name not in names:
            names.append(env.unwrapped.scene.name)
    policy = PlannerPolicy(env.unwrapped)
    samples, steps, successes, met = [(0, rss_mb())], 0, 0, set()
    for i in range(1, n + 1):
        options = {"scene": names[i % cycle]} if cycle else None
        obs, info = env.reset(seed=i, options=options)
        met.add(env.unwrapped.scene.name)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs, info))
            steps += 1
            done = terminated or truncated
        successes += bool(info["is_success"])
        samples.append((i, rss_mb()))
    env.close()
    return samples, {"macro_actions": steps, "successes": successes, "scenes": len(met)}


def measure_vector(n_envs: int, n: int) -> list[tuple[int, float]]:
    import functools

    from gymnasium.vector import AsyncVectorEnv

    from utamp_gym.rl.envs import make_env

    fns = [functools.partial(make_env, ENV_ID, grounding="physics", obs_keys=None)] * n_envs
    vec = AsyncVectorEnv(fns)

    def total() -> float:
        return rss_mb() + sum(rss_mb(p.pid) for p in vec.processes)

    samples = [(0, total())]
    for i in range(1, n + 1):
        vec.reset(seed=i * n_envs)
        samples.append((i, total()))
    vec.close()
    return samples


# ---------------------------------------------------------------- figures
def slope_per_1000(samples: list[tuple[int, float]], after: int) -> float:
    """Least-squares RSS growth (MB) per 1,000 iterations over samples past `after`."""
    pts = [(i, m) for i, m in samples if i >= after]
    if len(pts) < 2:
        return float("nan")
    mx = sum(i for i, _ in pts) / len(pts)
    my = sum(m for _, m in pts) / len(pts)
    var = sum((i - mx) ** 2 for i, _ in pts)
    return 1000 * sum((i - mx) * (m - my) for i, m in pts) / var


def growth_over_last_half(samples: list[tuple[int, float]]) -> float:
    """RSS at the end minus RSS halfway (MB)."""
    n = samples[-1][0]
    half = min(samples, key=lambda s: abs(s[0] - n / 2))
    return samples[-1][1] - half[1]


def _child(part: str, args: argparse.Namespace) -> dict[str, Any]:
    """Run one measurement in a fresh interpreter; its JSON result."""
    cmd = [sys.executable, __file__, "--part", part]
    cmd += ["--resets", str(args.resets), "--episodes", str(args.episodes)]
    cmd += ["--repeat-scenes", str(args.repeat_scenes)]
    cmd += ["--vector-envs", str(args.vector_envs), "--vector-resets", str(args.vector_resets)]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"the {part} measurement failed:\n{done.stderr}")
    result = json.loads(done.stdout.splitlines()[-1])
    result["wall_s"] = round(time.perf_counter() - start, 1)
    return result


def _run_part(args: argparse.Namespace) -> None:
    if args.part == "resets":
        out: dict[str, Any] = {"samples": measure_resets(args.resets)}
    elif args.part in ("episodes", "repeat"):
        cycle = args.repeat_scenes if args.part == "repeat" else 0
        samples, counts = measure_episodes(args.episodes, cycle)
        out = {"samples": samples, **counts}
    else:
        out = {"samples": measure_vector(args.vector_envs, args.vector_resets)}
    print(json.dumps(out))


def _row(
    measurement: str, part: dict[str, Any], growth_mb: float, growth: str, per: str = ""
) -> dict[str, Any]:
    """One table row: RSS at the first and last sample of `part`, and its growth (MB) against
    `TARGET_MB` (`per`: the target's unit, e.g. " per 1,000 resets")."""
    return {
        "measurement": measurement,
        "start_mb": part["samples"][0][1],
        "end_mb": part["samples"][-1][1],
        "growth": f"{growth_mb:+.1f} MB {growth}",
        "growth_mb": growth_mb,
        "target": f"<= {TARGET_MB:g} MB{per}",
        "met": growth_mb <= TARGET_MB,
        "wall_s": part["wall_s"],
    }


def report(args: argparse.Namespace) -> dict[str, Any]:
    parts = {name: _child(name, args) for name in PARTS}
    resets, episodes, repeat, vector = parts.values()
    last = args.episodes - args.episodes // 2
    rows = [
        _row(
            f"{ENV_ID} physics: {args.resets} resets",
            resets,
            slope_per_1000(resets["samples"], after=500),
            "per 1,000 resets after the first 500",
            per=" per 1,000 resets",
        ),
        _row(
            f"{ENV_ID} physics: {args.episodes} planner-policy episodes "
            f"({episodes['macro_actions']} macro steps, {episodes['successes']} successes, "
            f"{episodes['scenes']} scenes met)",
            episodes,
            growth_over_last_half(episodes["samples"]),
            f"over the last {last}",
        ),
        _row(
            f"{ENV_ID} physics: {args.episodes} planner-policy episodes over "
            f"{repeat['scenes']} scenes, in turn ({repeat['macro_actions']} macro steps, "
            f"{repeat['successes']} successes)",
            repeat,
            growth_over_last_half(repeat["samples"]),
            f"over the last {last}",
        ),
        _row(
            f"AsyncVectorEnv of {args.vector_envs} physics envs: "
            f"{args.vector_resets} resets (parent + workers)",
            vector,
            growth_over_last_half(vector["samples"]),
            f"over the last {args.vector_resets - args.vector_resets // 2} resets",
        ),
    ]
    return {
        "env_id": ENV_ID,
        "python": platform.python_version(),
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs",
        "load_average_at_end": round(os.getloadavg()[0], 2),
        "rows": rows,
        "samples": {name: part["samples"] for name, part in parts.items()},
    }


def to_markdown(data: dict[str, Any]) -> str:
    lines = [
        "| measurement | RSS at start (MB) | RSS at end (MB) | growth | target | met |",
        "|---|---:|---:|---|---|---|",
    ]
    for r in data["rows"]:
        met = "yes" if r["met"] else "**no**"
        lines.append(
            f"| {r['measurement']} | {r['start_mb']:.0f} | {r['end_mb']:.0f} | {r['growth']} "
            f"| {r['target']} | {met} |"
        )
    lines.append("")
    lines.append(
        f"Written by `benchmarks/memory.py` (Python {data['python']}, {data['machine']}; "
        "resident set size from /proc, each measurement in a fresh process)."
    )
    return "\n".join(lines) + "\n"


def build_parser() -> argparse.ArgumentParser:
    """This script's options (tests check recorded result commands against them)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resets", type=int, default=2000)
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--repeat-scenes", type=int, default=10)
    ap.add_argument("--vector-envs", type=int, default=4)
    ap.add_argument("--vector-resets", type=int, default=100)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    ap.add_argument("--part", choices=PARTS, help=argparse.SUPPRESS)
    return ap


def main() -> None:
    args = build_parser().parse_args()
    commit()  # the provenance of what this run writes: the code as it is now
    if args.part:
        _run_part(args)
        return
    data = report(args)
    table = to_markdown(data)
    print(table, end="")
    args.out.mkdir(parents=True, exist_ok=True)
    prov = write_json(args.out / "memory.json", data, indent=1)
    write_markdown(args.out / "memory.md", table, prov)
    print(f"wrote {args.out / 'memory.json'} and {args.out / 'memory.md'}")
    if not all(r["met"] for r in data["rows"]):
        sys.exit(1)


if __name__ == "__main__":
    main()
