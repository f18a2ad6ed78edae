"""What the symbolic env's per-step shortcuts must keep: the same answers as the plain forms.

`SymbolicState.dead_end` reads the first applicable action off `argmax` instead of `any()`;
``info["anomalies"]`` without anomalies is a copy of one cached all-empty dict per scene;
`Scene.tower_base` and `Scene.object_names` are computed once per scene.
"""

from __future__ import annotations

import numpy as np

from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.state import SymbolicState


def test_dead_end_is_no_applicable_action_along_random_walks() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic", affordances="noisy", noise=0.3)
    rng = np.random.default_rng(0)
    seen = set()
    for seed in range(30):
        _, info = env.reset(seed=seed)
        for _ in range(40):
            state = env._state
            assert state.dead_end() == (not state.applicable_mask().any())
            seen.add(state.dead_end())
            valid = np.flatnonzero(info["action_mask"])
            if not len(valid):
                break
            _, _, terminated, truncated, info = env.step(int(rng.choice(valid)))
            if terminated or truncated:
                break
    assert seen == {True, False}  # both answers met


def test_dead_end_of_an_empty_mask() -> None:
    state = SymbolicState.__new__(SymbolicState)
    state._mask = np.zeros(0, bool)
    assert state.dead_end()
    state._mask = np.array([False, False, True])
    assert not state.dead_end()
    state._mask = np.array([True, False])
    assert not state.dead_end()


def test_info_anomalies_list_every_object_in_a_fresh_dict_each_step() -> None:
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic")
    _, first = env.reset(seed=3)
    names = [o.name for o in env.scene.objects]
    assert first["anomalies"] == dict.fromkeys(names, "")
    assert list(first["anomalies"]) == names
    first["anomalies"][names[0]] = "changed by a caller"
    _, _, _, _, info = env.step(int(np.flatnonzero(first["action_mask"])[0]))
    assert info["anomalies"] == dict.fromkeys(names, "")
    assert info["anomalies"] is not first["anomalies"]
    assert env.scene.object_names == tuple(names)
    trays = [o.name for o in env.scene.objects if o.type == "wooden-tray"]
    assert [env.scene.tower_base] == trays
