"""Why-not explanations: the smallest set of affordance corrections that unblocks a scene."""

from __future__ import annotations

import json

from utamp_gym.cli import main
from utamp_gym.eval.explain import explain_unsolvable, format_fact
from utamp_gym.eval.runner import EvalTask, run_task
from utamp_gym.eval.solvability import SolvabilityOracle
from utamp_gym.planning.methods import ground_truth_for, plan_scene
from utamp_gym.suites import get_scene, suite_scenes

PAN_SUPPORTS_BOARD = ("isP2PSupportive", "on", "frying-pan", "under", "cutting-board")
SCENE = "pick-place/013"  # tray/pan | board: the board must go onto the pan


def _unsolved_noisy_seed(scene: str, noise: float = 0.3) -> int:
    for seed in range(100):
        if not plan_scene(get_scene(scene), "utamp2-noisy", seed=seed, noise=noise).solved:
            return seed
    raise AssertionError("no unsolvable noisy detection in 100 seeds")


def test_removed_pan_supports_board_is_named() -> None:
    scene = get_scene(SCENE)
    assert {o.type for o in scene.objects} >= {"frying-pan", "cutting-board"}
    detected = ground_truth_for(scene) - {PAN_SUPPORTS_BOARD}
    expl = explain_unsolvable(scene, detected)
    assert expl.found and expl.smallest
    assert expl.missing == (PAN_SUPPORTS_BOARD,) and expl.spurious == ()
    assert "isP2PSupportive(on, frying-pan, under, cutting-board)" in expl.message


def test_two_missing_facts_are_both_required() -> None:
    scene = get_scene(SCENE)
    gone = {PAN_SUPPORTS_BOARD, ("canLift", "cutting-board", "handle")}
    expl = explain_unsolvable(scene, ground_truth_for(scene) - gone)
    assert set(expl.missing) == gone and expl.smallest


def test_spurious_can_lift_blocks_sliding() -> None:
    scene = suite_scenes("sliding")[0]
    members = ("handle-front", "handle-back", "edge-left", "edge-right")
    spurious = {("canLift", "wooden-tray", m) for m in members}
    expl = explain_unsolvable(scene, ground_truth_for(scene) | spurious)
    assert expl.found and not expl.missing
    assert expl.spurious and set(expl.spurious) <= spurious


def test_oracle_agrees_with_the_planner() -> None:
    scene = get_scene(SCENE)
    gt = ground_truth_for(scene)
    oracle = SolvabilityOracle(scene, gt)
    assert oracle(gt)
    assert not oracle(gt - {PAN_SUPPORTS_BOARD})
    text = "isP2PSupportive(on, frying-pan, under, cutting-board)"
    assert format_fact(PAN_SUPPORTS_BOARD) == text


def test_failure_reason_in_results_names_the_missing_facts() -> None:
    seed = _unsolved_noisy_seed(SCENE)
    task = EvalTask(SCENE, "utamp2-noisy", seed=seed, grounding="symbolic", noise=0.3)
    row = run_task(task)
    assert not row.solved and not row.crashed
    assert row.failure_reason.startswith("not solved: ")
    assert "missing affordance facts: " in row.failure_reason or "spurious" in row.failure_reason


def test_plan_explain_cli(capsys) -> None:
    seed = _unsolved_noisy_seed(SCENE)
    args = ["plan", SCENE, "--method", "utamp2-noisy", "--noise", "0.3", "--seed", str(seed)]
    assert main([*args, "--explain"]) == 0
    out = capsys.readouterr().out
    assert "not solved" in out and "why not: " in out
    assert main([*args, "--explain", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["solved"] is False and data["explanation"]["found"]
    assert data["explanation"]["missing"] or data["explanation"]["spurious"]
    assert main(["plan", SCENE, "--explain", "--json"]) == 0  # solved: nothing to explain
    assert json.loads(capsys.readouterr().out)["explanation"] is None
