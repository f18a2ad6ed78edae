"""Choosing the splits' seeds and writing their file: ``python -m utamp_gym.suites.procedural
select|digest|check``."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

from utamp_gym.planning.methods import plan_scene
from utamp_gym.resources import asset_path
from utamp_gym.suites.procedural.layout import (
    generate_scene,
)
from utamp_gym.suites.procedural.seeds import (
    SAMPLE_STEP,
    _seed_table,
    split_digest,
    split_hash,
    split_scene,
)
from utamp_gym.suites.procedural.spec import (
    SEEDS_FILE,
    SIZES,
    SPLITS,
    UNACHIEVABLE_SHARE,
    Generated,
    NoLayout,
)


def _planner_agrees(g: Generated) -> bool:
    """Fast Downward with the rules' affordances solves the scene iff it is called achievable."""
    return plan_scene(g.scene, "utamp2-rules", timeout=60.0).solved == g.achievable


def select_seeds(split: str, n: int, share: float = UNACHIEVABLE_SHARE) -> dict[str, Any]:
    """The first seeds (0, 1, ...) with a valid layout, `n` in all of which ``share`` are
    unachievable (the rest achievable); each label is checked against the planner."""
    want_bad = round(n * share)
    want_good = n - want_bad
    good = bad = 0
    seeds: list[int] = []
    skipped = {"layout": 0, "planner disagrees": 0, "share full": 0}
    seed = -1
    while good < want_good or bad < want_bad:
        seed += 1
        try:
            g = generate_scene(split, seed)
        except NoLayout:
            skipped["layout"] += 1
            continue
        if (g.achievable and good >= want_good) or (not g.achievable and bad >= want_bad):
            skipped["share full"] += 1
            continue
        if not _planner_agrees(g):
            skipped["planner disagrees"] += 1
            continue
        seeds.append(seed)
        good += g.achievable
        bad += not g.achievable
    return {"seeds": seeds, "achievable": good, "unachievable": bad, "skipped": skipped}


def _write_seed_file() -> None:
    import tomli_w

    out: dict[str, Any] = {}
    for split in SPLITS:
        chosen = select_seeds(split, SIZES[split])
        out[split] = {
            "seeds": chosen["seeds"],
            "achievable": chosen["achievable"],
            "unachievable": chosen["unachievable"],
        }
        print(split, {k: v for k, v in chosen.items() if k != "seeds"}, file=sys.stderr)
    asset_path(*SEEDS_FILE[:-1]).joinpath(SEEDS_FILE[-1]).write_text(_HEADER + tomli_w.dumps(out))
    _write_digests()


def _write_digests() -> None:
    import tomli_w

    _seed_table.cache_clear()
    split_scene.cache_clear()
    out = dict(_seed_table())
    for split in SPLITS:
        out[split] = {
            **out[split],
            "sha256": split_digest(split),
            "sample_sha256": split_digest(split, SAMPLE_STEP),
        }
    asset_path(*SEEDS_FILE).write_text(_HEADER + tomli_w.dumps(out))
    _seed_table.cache_clear()


_HEADER = """\
# The splits of procedural-v1: fixed lists of scene seeds (utamp_gym.suites.procedural).
# Scene procedural-v1/<split>/NNNN is generate_scene(split, seeds[NNNN]); sha256 is the digest
# of the split's scene files (split_digest), which tests/test_procedural.py regenerates.
# Written by `python -m utamp_gym.suites.procedural select` (do not edit by hand).
"""


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args == ["select"]:
        _write_seed_file()
        return 0
    if args == ["digest"]:
        _write_digests()
        return 0
    if args == ["check"]:
        bad = [s for s in SPLITS if split_digest(s) != split_hash(s)]
        print("ok" if not bad else f"differ: {', '.join(bad)}")
        return 1 if bad else 0
    print("usage: python -m utamp_gym.suites.procedural select|digest|check", file=sys.stderr)
    return 2
