"""Plans and SAS tasks stay what they were: every scene of the paper's suites and a sample
of each procedural-v1 split, planned with UTAMP-2-GT, must give the recorded plan and the
recorded SAS task, byte for byte; the pick-place suite under UTAMP-1 its recorded SAS task
(not searched: a five-object UTAMP-1 blind search takes seconds to minutes, and the search
binary reads nothing but that text).

The record (``tests/data/expected_plans.json``) was written by this file's ``record`` on
commit 2c0b0d1, before the planner's speed work (`symbolic.joins`, `symbolic.store`):
a change that alters a plan or the SAS text the search binary reads fails here. Re-record
only for a change meant to alter plans:
``PYTHONPATH=. python tests/test_plan_regression.py``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import pytest

from utamp_gym.planning import state_planner
from utamp_gym.planning.downward import PlanResult
from utamp_gym.planning.methods import plan_scene
from utamp_gym.planning.state_planner import StatePlanner
from utamp_gym.suites import resolve_scene, suite_scenes

RECORD = Path(__file__).parent / "data" / "expected_plans.json"
#: every k-th scene of each procedural split (the record's sample)
PROCEDURAL_STRIDE = 40
PROCEDURAL = ("train", "test-instances", "test-families", "test-count")


def cases() -> list[tuple[str, str]]:
    """(scene, method) pairs of the record."""
    paper = ("pick-place", "sliding")
    out = [(s.name, "utamp2-gt") for suite in paper for s in suite_scenes(suite)]
    out += [(s.name, "utamp1") for s in suite_scenes("pick-place")]
    for split in PROCEDURAL:
        names = [s.name for s in suite_scenes(f"procedural-v1/{split}")]
        out += [(n, "utamp2-gt") for n in names[::PROCEDURAL_STRIDE]]
    return out


def planned(scene: str, method: str) -> dict[str, object]:
    """The plan of `scene` (a fresh planner: a cached task would depend on the scenes planned
    before) and the digest of the SAS text its search read."""
    texts: list[str] = []
    search = state_planner.search_sas

    def keep(text: str, **kw: object) -> object:
        texts.append(text)
        if method == "utamp1":
            return PlanResult(False, (), None, 0.0, 0.0, 0.0, "not searched", None)
        return search(text, **kw)

    state_planner.search_sas = keep
    try:
        domain = "utamp1" if method == "utamp1" else "utamp2"
        out = plan_scene(resolve_scene(scene), method, planner=StatePlanner(domain))
    finally:
        state_planner.search_sas = search
    sas = hashlib.sha256(texts[0].encode()).hexdigest()[:16] if texts else None
    if method == "utamp1":
        return {"sas": sas}
    return {"solved": out.solved, "plan": list(out.plan), "sas": sas, "reason": out.reason}


def _expected() -> dict[str, dict[str, object]]:
    return json.loads(RECORD.read_text())


@pytest.mark.slow
def test_every_recorded_plan_and_sas_task_is_unchanged() -> None:
    expected = _expected()
    changed = [k for k, v in expected.items() if planned(*k.split(" ")) != v]
    assert not changed, f"{len(changed)} plans or SAS tasks changed: {changed[:5]}"


@pytest.mark.parametrize("suite", ["pick-place", "sliding", "procedural-v1"])
def test_a_sample_of_recorded_plans_and_sas_tasks_is_unchanged(suite: str) -> None:
    expected = _expected()
    keys = [k for k in expected if k.startswith(suite)][::4]
    assert len(keys) >= 4
    for key in keys:
        assert planned(*key.split(" ")) == expected[key], key


def test_the_record_covers_the_suites_and_the_splits() -> None:
    keys = set(_expected())
    assert keys == {f"{s} {m}" for s, m in cases()}
    assert sum(k.endswith("utamp2-gt") for k in keys) > 150


def record() -> None:
    data = {f"{s} {m}": planned(s, m) for s, m in cases()}
    RECORD.write_text(json.dumps(data, indent=0, sort_keys=True) + "\n")
    print(f"recorded {len(data)} plans in {RECORD}")


if __name__ == "__main__":
    record()
    sys.exit(0)
