"""Plans of an extended domain are checked and played in that domain (issue #38/#39).

`procedural-v2/train/0007` is achievable only through a rim pinch (``canLift`` on a rim
member), which U-TAMP-2's ground truth does not have: played in a U-TAMP-2 env, or checked
against U-TAMP-2's ground truth, the rules' own plan was called invalid.
"""

from __future__ import annotations

import pytest

from utamp_gym.agents.runs import execute_plan, run_episode
from utamp_gym.planning.crosscheck import check_against_ground_truth, checking_domain
from utamp_gym.planning.methods import plan_scene
from utamp_gym.suites import resolve_scene

SCENE = "procedural-v2/train/0007"


@pytest.fixture(scope="module")
def planned():
    scene = resolve_scene(SCENE)
    outcome = plan_scene(scene, "utamp2x-rules")
    assert outcome.solved
    return scene, outcome


def test_the_plan_needs_the_extended_ground_truth(planned) -> None:
    scene, outcome = planned
    assert any("rim" in step for step in outcome.plan)
    assert check_against_ground_truth(scene, outcome.plan, "utamp2x").valid
    assert not check_against_ground_truth(scene, outcome.plan).valid  # U-TAMP-2's refuses


def test_the_plan_plays_in_an_env_of_its_domain(planned) -> None:
    scene, outcome = planned
    ex = execute_plan(scene, outcome.plan, grounding="symbolic", domain="utamp2x")
    assert ex.success, ex.failure_reason
    paper = execute_plan(scene, outcome.plan, grounding="symbolic")
    assert not paper.success and "ground truth" in paper.failure_reason


def test_run_episode_plays_in_the_methods_domain() -> None:
    result = run_episode(SCENE, "utamp2x-rules")  # physics
    assert result.success, result.failure


def test_only_extended_domains_keep_their_own() -> None:
    assert checking_domain("utamp2x") == "utamp2x"
    assert checking_domain("utamp1") == checking_domain("utamp2") == "utamp2"
