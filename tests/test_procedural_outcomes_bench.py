"""benchmarks/procedural_outcomes.py: the picks the rules forbid, by the rule that refuses them
(issue #39's recall line), without running physics."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

outcomes = readme.load_script("benchmarks/procedural_outcomes.py")

SCENE = "procedural-v1/train/0192"  # obj3: a tumbler standing inverted on the tray


@pytest.mark.parametrize(
    ("action", "kind"),
    [
        # granted as (under, front, back): the same two grasp poses, fingers named the other way
        ("(pick-support obj3 obj3-body under back front back under base on on)", "finger order"),
        # the palm on the round side: a side grasp (the rules grant the palm on on/under only)
        ("(pick-support obj3 obj3-body back left right back under base on on)", "side grasp"),
    ],
)
def test_a_forbidden_pick_is_put_down_to_the_rule_that_refuses_it(action, kind):
    reason = "canGraspFrom(...) is false (ground truth)"
    assert outcomes.pick_refusal_kind(SCENE, action, reason, "utamp2x") == kind


def test_the_report_counts_the_forbidden_picks_physics_carried_out():
    def pair(action: str, allowed: bool, physics: bool) -> object:
        return outcomes.Pair(
            split="train",
            scene=SCENE,
            step=0,
            action=action,
            kind="pick-support",
            family="tumbler",
            support_family="",
            allowed=allowed,
            rules_reason="" if allowed else "canGraspFrom(...) is false (ground truth)",
            physics=physics,
            physics_reason="",
            step_s=0.1,
        )

    mirror = "(pick-support obj3 obj3-body under back front back under base on on)"
    side = "(pick-support obj3 obj3-body back left right back under base on on)"
    granted = "(pick-support obj3 obj3-body under front back back under base on on)"
    pairs = [pair(mirror, False, True), pair(side, False, False), pair(granted, True, True)]
    summary = outcomes.summarize(pairs, "utamp2x")
    assert (summary["forbidden_picks"], summary["forbidden_picks_physics_ok"]) == (2, 1)
    # the mirrored pick is the granted grasp under another name: not a refused grasp
    assert (summary["forbidden_grasps"], summary["forbidden_grasps_physics_ok"]) == (1, 0)
    by = summary["forbidden_picks_by_refusal"]
    assert by["finger order"] == {"forbidden": 1, "forbidden_ok": 1}
    assert by["side grasp"] == {"forbidden": 1, "forbidden_ok": 0}
    args = argparse.Namespace(
        pairs=3, splits="train", seed=0, max_steps=12, workers=1, domain="utamp2x"
    )
    text = outcomes.to_markdown(summary, args, 1.0)
    assert "of the picks they forbid, physics carried out 1/2 (50.0%) (target ≤ 5%)" in text
    assert (
        "of the grasps they refuse under every name" in text
        and "grant: the same grasp), 0/1 (0.0%)." in text
    )
    assert "| side grasp | 1 | 0/1 (0.0%) |" in text
