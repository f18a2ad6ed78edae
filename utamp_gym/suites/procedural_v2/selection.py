"""Choosing procedural-v2's seeds and writing its split file:
``python -m utamp_gym.suites.procedural_v2 select SPLIT OUT.json [N [RELAX_AFTER [LOG [ONLY]]]]``
(one split, its labels checked; `select_seeds`' `relax_after`, `resume` and `only`), then
``write OUT.json ...`` (the split file with digests) and ``check``.

`select_seeds` walks the seeds 0, 1, ... and keeps a seed when its scene has a layout and a
goal, the planner labels the goal (`labels.label`, no time-out), Fast Downward's translator
agrees (`labels.fd_agrees`), and its quota is not full: each template of the split gets an
equal share of the achievable goals, `UNACHIEVABLE_SHARE` of the split is unachievable
(`hard`: none, and every plan at least `HARD_MIN_ACTIONS` actions long).
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from utamp_gym.errors import UnknownNameError
from utamp_gym.resources import assets_dir
from utamp_gym.suites.procedural.spec import NoLayout
from utamp_gym.suites.procedural_v2.labels import fd_agrees, label
from utamp_gym.suites.procedural_v2.scenes import generate_scene
from utamp_gym.suites.procedural_v2.seeds import (
    SAMPLE_STEP,
    _seed_table,
    available_splits,
    split_digest,
    split_hash,
)
from utamp_gym.suites.procedural_v2.spec import (
    DOMAIN,
    HARD_MIN_ACTIONS,
    HELD_OUT_COMPOSITIONS,
    HELD_OUT_TEMPLATES,
    LABEL_METHOD,
    SEEDS_FILE,
    SIZES,
    SPLIT_TEMPLATES,
    SPLITS,
    UNACHIEVABLE_SHARE,
)


def select_seeds(
    split: str,
    n: int,
    *,
    check_fd: bool = True,
    log: Any = None,
    relax_after: int | None = None,
    resume: Sequence[tuple[int, str, bool, int]] = (),
    only: Sequence[str] = (),
) -> dict[str, Any]:
    """The first `n` seeds that fill the split's quotas (module docstring), with labels.

    After seed `relax_after` the per-template quotas no longer hold (a template whose goals
    are seldom achievable in a split, the tower of 6-8 objects in test-count, cannot stall
    it); `resume` continues a run from its kept (seed, template, achievable, plan length);
    `only`: after the resumed seeds, keep goals of these templates alone (the hard suite's
    ``restack``, seldom achievable, extended to `SIZES`' count after its first 24 scenes)."""
    templates = SPLIT_TEMPLATES[split]
    share = 0.0 if split == "hard" else UNACHIEVABLE_SHARE
    want_bad = round(n * share)
    per_template = math.ceil((n - want_bad) / len(templates))
    good = dict.fromkeys(templates, 0)
    bad = 0
    kept: list[tuple[int, bool, int]] = []
    skipped = {"layout": 0, "timed out": 0, "fd disagrees": 0, "share full": 0, "short": 0}
    seed = -1
    for seed, template, ok, length in resume:
        kept.append((seed, ok, length))
        good[template] += ok
        bad += not ok
    unknown = sorted(set(only) - set(templates))
    if unknown:
        raise UnknownNameError(f"template of split {split}", unknown[0], templates)
    extended_after = seed if only else None
    while len(kept) < n:
        seed += 1
        if relax_after is not None and seed > relax_after:
            per_template = n
        try:
            g = generate_scene(split, seed)
        except NoLayout:
            skipped["layout"] += 1
            continue
        if (good[g.template] >= per_template and bad >= want_bad) or (
            only and g.template not in only
        ):
            skipped["share full"] += 1
            continue
        lab = label(g.scene)
        if lab.timed_out:
            skipped["timed out"] += 1
            continue
        full = good[g.template] >= per_template if lab.achievable else bad >= want_bad
        if full:
            skipped["share full"] += 1
            continue
        if split == "hard" and lab.plan_length < HARD_MIN_ACTIONS:
            skipped["short"] += 1
            continue
        if check_fd and fd_agrees(g.scene, lab.achievable) is not True:
            skipped["fd disagrees"] += 1
            continue
        kept.append((seed, lab.achievable, lab.plan_length))
        if lab.achievable:
            good[g.template] += 1
        else:
            bad += 1
        if log is not None:
            print(split, len(kept), seed, g.template, lab, file=log, flush=True)
    return {
        "seeds": [s for s, _, _ in kept],
        "achievable": [a for _, a, _ in kept],
        "plan_length": [p for _, _, p in kept],
        "per_template": good,
        "unachievable": bad,
        "skipped": skipped,
        "fd_checked": check_fd,
        "relaxed_after_seed": relax_after,
        **({"only": list(only), "only_after_seed": extended_after} if only else {}),
    }


_HEADER = """\
# The splits of procedural-v2: fixed lists of scene seeds with their goals' labels
# (utamp_gym.suites.procedural_v2). Scene procedural-v2/<split>/NNNN is
# generate_scene(split, seeds[NNNN]), its goal in the scene; `achievable` / `plan_length`
# are the planner's (`labeller`) under `domain`, checked against Fast Downward's translator;
# sha256 is the digest of the split's scene files (split_digest). Held out from train:
# templates {held_out}, compositions {compositions} (test-tasks holds only these).
# Written by `python -m utamp_gym.suites.procedural_v2 write` (do not edit by hand).
"""


def write_split_file(parts: Sequence[dict[str, Any]]) -> None:
    """The split file from `select` outputs (one JSON object per split), with digests."""
    import tomli_w

    out: dict[str, Any] = {}
    for part in sorted(parts, key=lambda p: SPLITS.index(p["split"])):
        split = part["split"]
        seeds = tuple(part["seeds"])
        out[split] = {
            "domain": DOMAIN,
            "labeller": LABEL_METHOD,
            "labels_checked_with_fd_translator": bool(part["fd_checked"]),
            **(
                {"template_quota_relaxed_after_seed": part["relaxed_after_seed"]}
                if part.get("relaxed_after_seed") is not None
                else {}
            ),
            **(
                {
                    "only_templates_after_seed": part["only_after_seed"],
                    "only_templates": part["only"],
                }
                if part.get("only")
                else {}
            ),
            "templates": list(SPLIT_TEMPLATES[split]),
            "seeds": list(seeds),
            "achievable": part["achievable"],
            "plan_length": part["plan_length"],
            "sha256": split_digest(split, 1, seeds),
            "sample_sha256": split_digest(split, SAMPLE_STEP, seeds),
        }
    header = _HEADER.format(
        held_out=", ".join(HELD_OUT_TEMPLATES), compositions=", ".join(HELD_OUT_COMPOSITIONS)
    )
    assets_dir().joinpath(*SEEDS_FILE).write_text(header + tomli_w.dumps(out))
    _seed_table.cache_clear()


def _log_entry(line: str) -> tuple[int, str, bool, int]:
    """(seed, template, achievable, plan length) of a line `select_seeds` logged."""
    words = line.split()
    return (int(words[2]), words[3], "achievable=True" in line,
            int(line.split("plan_length=")[1].split(",")[0]))  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if 3 <= len(args) <= 7 and args[0] == "select" and args[1] in SPLITS:
        n = int(args[3]) if len(args) >= 4 else SIZES[args[1]]
        relax = int(args[4]) if len(args) >= 5 else None  # ... N RELAX_AFTER
        resume = []
        if len(args) >= 6:  # ... N RELAX_AFTER LOG: continue the run that LOG records
            resume = [_log_entry(line) for line in Path(args[5]).read_text().splitlines()]
        only = args[6].split(",") if len(args) == 7 else []  # ... LOG ONLY: these templates
        chosen = select_seeds(
            args[1], n, log=sys.stderr, relax_after=relax, resume=resume, only=only
        )
        with open(args[2], "w") as f:
            json.dump({"split": args[1], **chosen}, f)
        return 0
    if len(args) >= 2 and args[0] == "write":
        write_split_file([json.loads(Path(p).read_text()) for p in args[1:]])
        return 0
    if args == ["check"]:
        bad = [s for s in available_splits() if split_digest(s) != split_hash(s)]
        print("ok" if not bad else f"differ: {', '.join(bad)}")
        return 1 if bad else 0
    print(
        "usage: python -m utamp_gym.suites.procedural_v2 select SPLIT OUT.json "
        "[N [RELAX_AFTER [LOG [ONLY]]]] | "
        "write OUT.json ... | check",
        file=sys.stderr,
    )
    return 2
