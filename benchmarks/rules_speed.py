"""Speed of the affordance rules, ours against an earlier commit, in one run.

The rules decide through their ``*_refusal`` twins (`utamp_gym.affordances.why`); a
decision asks with ``why=False`` so that it builds no reason. This measures what the scene
generator and the planners pay for the rules: `derive_affordances` over a set of types,
`object_facts` of each type and `p2p_supportive` between pairs, on the catalogue, the
extra objects and ``--instances`` procedural instances of every kitchenware family. The
earlier commit (``--base``) is exported with ``git archive`` into a temporary folder; each
side runs in its own process, the two alternating ``--rounds`` times, and each reports the
best of ``--repeats`` timings per workload (CPU time of the process) and a hash of every
decision, which must be equal: the same facts, grasps and p2p answers.

    python benchmarks/rules_speed.py [--base b63c8f1~1] [--instances 20] [--rounds 3]
        [--repeats 5]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WORKLOADS = ("derive", "object_facts", "p2p")


def worker(instances: int, repeats: int) -> dict[str, object]:
    """Run in the code under test (its `utamp_gym` first on the path): timings and hash."""
    from utamp_gym.affordances import rules
    from utamp_gym.kitchenware import FAMILIES, generate
    from utamp_gym.scene.catalogue import load_catalogue
    from utamp_gym.suites.generate import extra_catalogue

    types = [*load_catalogue().types.values(), *extra_catalogue().types.values()]
    for family in FAMILIES:
        types += [generate(family, "v1", i, validate=False) for i in range(instances)]
    subset = types[:60]

    def derive() -> object:
        return sorted(rules.derive_affordances(subset))

    def object_facts() -> object:
        return [sorted(rules.object_facts(t)) for t in types]

    def p2p() -> object:
        parts = ("on", "under")
        return bytes(
            rules.p2p_supportive(t2, p2, t1, p1)
            for t2 in subset
            for t1 in types
            for p2 in parts
            for p1 in parts
        )

    best: dict[str, float] = {}
    digest = hashlib.sha256()
    for name, fn in zip(WORKLOADS, (derive, object_facts, p2p), strict=True):
        times = []
        for _ in range(repeats):
            start = time.process_time()
            result = fn()
            times.append(time.process_time() - start)
        best[name] = min(times)
        digest.update(repr(result).encode())
    return {"types": len(types), "best_s": best, "decisions": digest.hexdigest()}


def _run(path: Path, instances: int, repeats: int) -> dict[str, object]:
    env = {**os.environ, "PYTHONPATH": str(path)}
    cmd = [sys.executable, __file__, "--worker", str(instances), str(repeats)]
    out = subprocess.run(cmd, env=env, cwd=path, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="b63c8f1~1", help="the earlier commit")
    ap.add_argument("--instances", type=int, default=20, help="instances of each family")
    ap.add_argument("--rounds", type=int, default=3, help="ours/base alternations")
    ap.add_argument("--repeats", type=int, default=5, help="timings per workload and run")
    ap.add_argument("--worker", nargs=2, type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(*args.worker)))
        return
    with tempfile.TemporaryDirectory(prefix="rules_speed_") as tmp:
        base = Path(tmp)
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", args.base, "utamp_gym", "assets", "envs"],
            capture_output=True,
            check=True,
        )
        subprocess.run(["tar", "-x", "-C", str(base)], input=archive.stdout, check=True)
        runs: dict[str, list[dict[str, object]]] = {"ours": [], "base": []}
        for _ in range(args.rounds):
            runs["ours"].append(_run(ROOT, args.instances, args.repeats))
            runs["base"].append(_run(base, args.instances, args.repeats))
    head = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    hashes = {side: {r["decisions"] for r in rs} for side, rs in runs.items()}
    same = len(hashes["ours"] | hashes["base"]) == 1
    print(f"rules speed: ours {head} vs base {args.base}; {runs['ours'][0]['types']} types")
    options = f"--instances {args.instances} --rounds {args.rounds} --repeats {args.repeats}"
    print(f"command: python benchmarks/rules_speed.py --base {args.base} {options}")
    print(f"{'workload':<14}{'ours (s)':>10}{'base (s)':>10}{'ours/base':>11}")
    for name in WORKLOADS:
        ours = statistics.median(r["best_s"][name] for r in runs["ours"])  # type: ignore[index]
        base_s = statistics.median(r["best_s"][name] for r in runs["base"])  # type: ignore[index]
        print(f"{name:<14}{ours:>10.3f}{base_s:>10.3f}{ours / base_s:>11.2f}")
    print(f"decisions identical: {same}")
    if not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
