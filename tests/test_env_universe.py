"""The action universe and the mask against a direct grounding of each episode's own problem."""

from __future__ import annotations

from types import MappingProxyType
from typing import Any

import numpy as np
import pytest

from utamp_gym.affordances.sources import affordances_for, ground_truth_for, scene_types
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.suites import suite_scenes
from utamp_gym.symbolic.atoms import parse_atom, possible_affordances, scene_atoms
from utamp_gym.symbolic.pddl import Problem
from utamp_gym.symbolic.reach import GroundOp, reachable_ops
from utamp_gym.symbolic.universe import UniverseKey, ground_universe


def direct_ops(env: UTampKitchenEnv) -> list[GroundOp]:
    """Ground the episode's own problem (its static atoms + current fluents) with reach."""
    domain = env.universe.domain  # the env's domain, or its geometric preconditions
    objects = scene_atoms(env.scene, (), env.options.domain, domain.fluent_predicates())[2]
    atoms = {*env.static_atoms, *env.true_atoms()}
    problem = Problem(
        "p",
        domain.name,
        MappingProxyType(dict.fromkeys(objects, "obj")),
        frozenset(map(parse_atom, atoms)),
        (),
    )
    return reachable_ops(domain, problem)[0]


def applicable(ops: list[GroundOp], state: set[str]) -> set[str]:
    return {
        f"({op.name})"
        for op in ops
        if all(str(a) in state for a in op.pre) and not any(str(a) in state for a in op.pre_neg)
    }


@pytest.mark.parametrize(
    "config",
    [
        {"suite": "pick-place"},
        {"suite": "sliding"},
        {"suite": "pick-place", "affordances": "noisy", "noise": 0.3},
        {"suite": "sliding", "affordances": "rules"},
        {"suite": "pick-place", "domain": "utamp1", "num_objects": 3},
        {"suite": "pick-place", "masks": "geometric"},
        {"suite": "sliding", "masks": "geometric"},
    ],
)
def test_mask_matches_the_episodes_own_grounding(config: dict[str, Any]) -> None:
    env = UTampKitchenEnv(grounding="symbolic", **config)
    rng = np.random.default_rng(0)
    for seed in range(3):
        _, info = env.reset(seed=seed)
        ops = direct_ops(env)  # everything any reachable state can apply
        for _ in range(25):
            state = set(env.true_atoms())
            mine = {env.action_strings[i] for i in np.flatnonzero(info["action_mask"])}
            assert mine == applicable(ops, state), env.scene.name
            if not mine:  # a dead end (noisy affordances): any step terminates
                assert env.step(0)[2]
                break
            _, _, terminated, _, info = env.step(rng.choice(np.flatnonzero(info["action_mask"])))
            if terminated:
                break


@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_universe_contains_every_scenes_reachable_ops(suite: str) -> None:
    universe = ground_universe(UniverseKey("utamp2", "gt", suite))
    domain = universe.domain
    for scene in suite_scenes(suite):
        static, fluent, objects = scene_atoms(
            scene, ground_truth_for(scene), "utamp2", domain.fluent_predicates()
        )
        problem = Problem(
            scene.name,
            domain.name,
            MappingProxyType(dict.fromkeys(objects, "obj")),
            frozenset(map(parse_atom, static | fluent)),
            (),
        )
        ops = reachable_ops(domain, problem)[0]
        missing = {f"({op.name})" for op in ops} - set(universe.actions)
        assert not missing, (scene.name, sorted(missing)[:3])


def test_possible_affordances_cover_noisy_detections() -> None:
    scene = suite_scenes("pick-place")[-1]
    superset = possible_affordances(scene_types(scene))
    rng = np.random.default_rng(0)
    for noise in (0.3, 1.0):
        for _ in range(50):
            facts = affordances_for(scene, "noisy", rng, noise)[0]
            assert facts <= superset
    assert ground_truth_for(scene) <= superset


def test_universe_is_cached_per_key_and_read_only() -> None:
    key = UniverseKey("utamp2", "gt", "pick-place")
    universe = ground_universe(key)
    assert ground_universe(UniverseKey("utamp2", "gt", "pick-place")) is universe
    assert not universe.static_pre.flags.writeable and not universe.check_flat.flags.writeable
    assert universe.index(" ( " + universe.actions[5][1:-1].upper() + " ) ") == 5
