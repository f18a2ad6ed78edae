"""benchmarks/v2_physics.py: what it counts from utamp eval's rows (no physics run here)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

from utamp_gym.suites.procedural_v2 import split_scenes  # noqa: E402

bench = readme.load_script("benchmarks/v2_physics.py")


def _row(name: str, solved: bool, success: bool, reason: str = "") -> dict[str, str]:
    flag = {True: "true", False: "false"}
    return {"scene": name, "seed": "0", "solved": flag[solved], "success": flag[success],
            "failure_reason": reason}  # fmt: skip


def test_summary_counts_planned_runs_templates_and_unsolvable_goals() -> None:
    scenes = split_scenes("test-tasks")
    names = [s.scene.name for s in scenes]
    good = [i for i, s in enumerate(scenes) if s.achievable][:3]
    bad = next(i for i, s in enumerate(scenes) if not s.achievable)
    rows = [_row(names[good[0]], True, True), _row(names[good[1]], True, True)]
    rows.append(_row(names[good[2]], True, False, "step 0 (pick x): obj1 slipped"))
    rows.append(_row(names[bad], True, False))  # an unachievable goal that was planned
    s = bench.summarize_split("test-tasks", rows)
    assert (s["scenes"], s["scenes_run"], s["runs"], s["planned"]) == (100, 4, 4, 4)
    assert s["planned_success"] == 2 and s["success_rate_of_planned"] == 0.5
    assert (s["unachievable_runs"], s["unachievable_reported_unsolvable"]) == (1, 0)
    assert [f["scene"] for f in s["failures"]] == [names[good[2]], names[bad]]
    assert sum(c.get("runs", 0) for c in s["by_template"].values()) == 4
    assert s["failures"][0]["template"] == scenes[good[2]].template
    below = bench.below_target([s])
    assert "test-tasks" in below and "test-tasks (an unachievable goal was planned)" in below
    text = bench.to_markdown([s], argparse.Namespace(seeds=1))
    assert "**2/4 (50.0%)**" in text and "obj1 slipped" in text


def test_eval_command_is_the_label_method_in_physics() -> None:
    args = bench.build_parser().parse_args(["--seeds", "2", "--out", "o"])
    cmd = bench.eval_command("hard", args)
    assert cmd[:5] == ["eval", "--suite", "procedural-v2/hard", "--methods", "utamp2x-rules"]
    assert "physics" in cmd and cmd[cmd.index("--out") + 1] == str(Path("o") / "hard")


def test_closed_loop_runs_the_planner_policy_and_writes_its_own_page() -> None:
    args = bench.build_parser().parse_args(["--closed-loop", "--out", "o"])
    assert "--closed-loop" in bench.eval_command("test-tasks", args)
    assert bench.page_stem(args) == "v2_physics_closed_loop"
    plain = bench.build_parser().parse_args([])
    assert "--closed-loop" not in bench.eval_command("test-tasks", plain)
    assert bench.page_stem(plain) == "v2_physics"
    scenes = split_scenes("test-tasks")
    good = [s.scene.name for s in scenes if s.achievable][:2]
    rows = [_row(good[0], True, True) | {"n_replans": "2"}, _row(good[1], True, True)]
    rows[1]["n_replans"] = "0"
    s = bench.summarize_split("test-tasks", rows)
    assert (s["replanned"], s["replanned_success"]) == (1, 1)
    text = bench.to_markdown([s], args)
    assert "closed loop" in text and "--closed-loop" in text and "| 1 (1) |" in text
    assert "closed loop" not in bench.to_markdown([s], plain)
