"""Mask modes: the geometric action space, the symbolic outcome model, masks "none"."""

from __future__ import annotations

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from utamp_gym.agents import PlannerPolicy
from utamp_gym.backend import MacroResult
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.options import MASKS
from utamp_gym.env.registry import register_envs
from utamp_gym.errors import UnknownNameError
from utamp_gym.symbolic.universe import UniverseKey, ground_universe

SIDE_GRASP = "(pick-support salt salt-body left back front"  # palm on the side, not the top


def geometric(suite: str = "pick-place", **kw: object) -> UTampKitchenEnv:
    return UTampKitchenEnv(suite=suite, grounding="symbolic", masks="geometric", **kw)


def first(env: UTampKitchenEnv, prefix: str, mask: np.ndarray) -> int:
    """The first action shown by `mask` whose PDDL text starts with `prefix`."""
    for i in np.flatnonzero(mask):
        if env.action_strings[i].startswith(prefix):
            return int(i)
    raise AssertionError(f"no allowed action starts with {prefix!r}")


@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_geometric_action_space_has_what_affordances_forbid(suite: str) -> None:
    affordance = ground_universe(UniverseKey("utamp2", "gt", suite))
    universe = ground_universe(UniverseKey("utamp2", "none", suite, (), "geometric"))
    actions = universe.actions
    assert any(a.startswith(SIDE_GRASP) for a in actions)
    assert any(a.startswith("(pick-support tray ") for a in actions)
    assert any(a.startswith("(place-support mug ") and " salt " in a for a in actions)
    assert len(actions) > 5 * len(affordance.actions)
    assert not any(a.startswith(SIDE_GRASP) for a in affordance.actions)
    assert not any(a.startswith("(pick-support tray ") for a in affordance.actions)


def test_geometric_universe_needs_utamp2_without_affordances() -> None:
    with pytest.raises(ValueError, match="utamp2"):
        UniverseKey("utamp1", "none", "pick-place", (), "geometric")
    with pytest.raises(UnknownNameError, match="geometric"):
        UniverseKey("utamp2", "gt", "pick-place", (), "physical")


def test_side_grasp_fails_symbolically_naming_the_false_affordance() -> None:
    env = geometric()
    _, info = env.reset(seed=0, options={"scene": "pick-place/004"})  # tray | salt
    before = env.true_atoms()
    _, reward, terminated, _, info = env.step(first(env, SIDE_GRASP, info["action_mask"]))
    reason = info["failure_reason"]
    assert reason == "canGraspFrom(salt, salt-body, left, back, front) is false (ground truth)"
    assert env.true_atoms() == before and not terminated and reward == 0.0
    assert not info["macro_result"]["executed"] and env.macro_result is None
    # a graspable member of the tray: the grasp holds, the 5 kg tray cannot be lifted
    handle = "(pick-support tray tray-handle-front on front back "
    _, _, _, _, info = env.step(first(env, handle, info["action_mask"]))
    assert info["failure_reason"] == "canLift(tray, tray-handle-front) is false (ground truth)"
    _, _, _, _, info = env.step(
        first(env, "(pick-support salt salt-body on left right ", info["action_mask"])
    )
    assert info["failure_reason"] == "" and "(oc in hand salt)" in env.true_atoms()


def test_placing_on_a_round_top_fails_on_its_affordance() -> None:
    env = geometric()
    _, info = env.reset(seed=0, options={"scene": "pick-place/023"})  # tray | salt | mug(inv)
    _, _, _, _, info = env.step(
        first(env, "(pick-support mug mug-handle under left right ", info["action_mask"])
    )
    assert info["failure_reason"] == ""
    before = env.true_atoms()
    on_salt = "(place-support mug mug-handle "
    for i in np.flatnonzero(info["action_mask"]):
        if env.action_strings[i].startswith(on_salt) and env.action_strings[i].endswith(
            " salt back on)"
        ):
            _, _, _, _, info = env.step(int(i))
            break
    else:
        raise AssertionError("placing the mug on the shaker's top is geometrically allowed")
    assert info["failure_reason"] == "isSupportive(salt, on) is false (ground truth)"
    assert env.true_atoms() == before


@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_outcome_model_agrees_with_the_affordance_env(suite: str) -> None:
    """A geometric step succeeds iff the same action is applicable in the U-TAMP-2 env under
    the ground truth, and then both envs reach the same atoms; in every state, the geometric
    mask and the outcome model's verdict together are exactly the U-TAMP-2 mask."""
    geo = geometric(suite)
    ref = UTampKitchenEnv(suite=suite, grounding="symbolic")
    rng = np.random.default_rng(0)
    successes = failures = 0
    for seed in range(6):
        _, info = geo.reset(seed=seed)
        _, ref_info = ref.reset(options={"scene": geo.scene.name})
        for _ in range(40):
            hold = geo.backend.outcome.affordances_hold()  # type: ignore[attr-defined]
            predicted = {geo.action_strings[i] for i in np.flatnonzero(info["action_mask"] & hold)}
            truth = {ref.action_strings[i] for i in np.flatnonzero(ref_info["action_mask"])}
            assert predicted == truth, geo.scene.name
            i = int(rng.choice(np.flatnonzero(info["action_mask"])))
            text = geo.action_strings[i]
            allowed = text in ref.universe.action_index and bool(
                ref_info["action_mask"][ref.universe.index(text)]
            )
            _, _, terminated, _, info = geo.step(i)
            assert (info["failure_reason"] == "") == allowed, (text, info["failure_reason"])
            if allowed:
                successes += 1
                _, _, _, _, ref_info = ref.step(ref.universe.index(text))
                assert set(geo.true_atoms()) == set(ref.true_atoms())
            else:
                failures += 1
            if terminated:
                break
    assert successes > 10 and failures > 10


def test_planner_plan_solves_the_geometric_env() -> None:
    env = gym.make("UTampKitchen-v0", grounding="symbolic", masks="geometric", num_objects=4)
    policy = PlannerPolicy(env)
    obs, info = env.reset(seed=3)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        assert info["failure_reason"] == ""
    assert terminated and reward == 1.0


def test_masks_none_shows_every_action_of_the_scene() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", masks="none", num_objects=2)
    _, info = env.reset(seed=0)
    names = {o.name for o in env.scene.objects}
    mask = info["action_mask"]
    assert 0 < mask.sum() < env.action_space.n
    for i, text in enumerate(env.action_strings):
        movers = {env.universe.roles[i][1], env.universe.roles[i][2]}
        objects = {o for o in movers if o in {"tray", "salt", "mug", "board", "pan"}}
        if not objects <= names:
            assert not mask[i], text
    geo = geometric(num_objects=2)
    _, geo_info = geo.reset(seed=0)
    assert geo.action_strings == env.action_strings  # one action space for both
    assert (geo_info["action_mask"] <= mask).all()
    # an allowed action whose geometric precondition is false fails on it, state unchanged
    place = first(env, "(place-support ", mask)
    before = env.true_atoms()
    _, _, _, _, info = env.step(place)
    assert info["failure_reason"].startswith("precondition (oc in hand ")
    assert info["failure_reason"].endswith("is false (fluent)")
    assert env.true_atoms() == before
    assert (info["action_mask"] == mask).all()  # fixed for the episode


@pytest.mark.parametrize("masks", MASKS)
@pytest.mark.parametrize("env_id", ["UTampKitchen-v0", "UTampKitchenSlide-v0"])
def test_check_env_passes_for_every_mask_mode(env_id: str, masks: str) -> None:
    register_envs()
    env = gym.make(env_id, grounding="symbolic", masks=masks)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # render modes are test_env's (they need a display); here: spaces, seeding, steps
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_bad_masks_are_rejected_with_the_valid_values() -> None:
    with pytest.raises(UnknownNameError) as err:
        UTampKitchenEnv(suite="pick-place", grounding="symbolic", masks="oracle")
    assert "affordances, geometric, none" in str(err.value)
    with pytest.raises(ValueError, match="domain='utamp2'"):
        UTampKitchenEnv(suite="pick-place", grounding="symbolic", masks="none", domain="utamp1")


@pytest.mark.physics
def test_forbidden_actions_reach_the_simulator_in_physics() -> None:
    """Physics, not the outcome model, decides what the geometric mask allows."""
    env = UTampKitchenEnv(suite="pick-place", masks="geometric")
    try:
        _, info = env.reset(seed=0, options={"scene": "pick-place/004"})  # tray | salt
        handle = "(pick-support tray tray-handle-front on front back "
        _, _, _, _, info = env.step(first(env, handle, info["action_mask"]))
        assert isinstance(env.unwrapped.macro_result, MacroResult)
        assert not env.unwrapped.macro_result.success  # 5 kg: the Panda cannot lift it
        assert info["failure_reason"] == env.unwrapped.macro_result.reason
        assert info["macro_result"]["executed"] and not info["macro_result"]["success"]
        assert "ground truth" not in info["failure_reason"]
        _, _, _, _, info = env.step(first(env, SIDE_GRASP, info["action_mask"]))
        assert isinstance(env.unwrapped.macro_result, MacroResult)
        assert (info["failure_reason"] == "") == env.unwrapped.macro_result.success
    finally:
        env.close()


def test_pickle_round_trip_keeps_the_outcome_model() -> None:
    env = geometric()
    _, info = env.reset(seed=0, options={"scene": "pick-place/004"})
    clone = pickle.loads(pickle.dumps(env))
    side = first(env, SIDE_GRASP, info["action_mask"])
    for e in (env, clone):
        _, _, _, _, step_info = e.step(side)
        assert step_info["failure_reason"].startswith("canGraspFrom(salt, salt-body, left")
    assert clone.true_atoms() == env.true_atoms()
