"""What the symbolic env's per-step shortcuts must keep: the same answers as the plain forms.

The mask comes from 64-bit words of literals (was: bits gathered and summed per op);
`SymbolicState.dead_end` reads the first applicable action off `argmax` instead of `any()`;
``info["anomalies"]`` without anomalies is a copy of one all-empty dict per episode; the
observation's ``symbolic`` vector is a copy of one kept per state (`Observer`);
`Scene.tower_base` and `Scene.object_names` are computed once per scene.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import utamp_gym  # noqa: F401  (registers the env ids)
from utamp_gym.env import observe
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.symbolic.state import SymbolicState


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


def reference_mask(state: SymbolicState) -> np.ndarray:
    """The mask as `SymbolicState._refresh` computed it before (commit 3675150): the extended
    bits unpacked, every op's literals gathered and summed with `np.add.reduceat`."""
    u = state.universe
    ok = u.static_ok(u.pack_static(state.static_atoms))
    lengths = np.where(ok, np.diff(u.check_ptr), 1)
    ptr = np.zeros(len(lengths) + 1, np.int64)
    np.cumsum(lengths, out=ptr[1:])
    row = np.repeat(np.arange(len(lengths)), lengths)
    src = u.check_ptr[row] + (np.arange(ptr[-1]) - ptr[row])
    flat = np.where(ok[row], u.check_flat[src], u.half + len(u.fluent_atoms))
    x = state.bits | ((~state.bits & ((1 << u.half) - 1)) << u.half)
    raw = np.frombuffer(x.to_bytes(2 * u.half // 8, "little"), np.uint8)
    ext = np.unpackbits(raw, bitorder="little").astype(np.intp)
    return np.add.reduceat(ext[flat], ptr[:-1]) == 0


def reference_vector(state: SymbolicState) -> np.ndarray:
    n = len(state.universe.fluent_atoms)
    return np.array([(state.bits >> j) & 1 for j in range(n)], np.int8)


@pytest.mark.parametrize(
    ("env_id", "options"),
    [
        ("UTampKitchen-v0", {}),
        ("UTampKitchen-v0", {"affordances": "noisy", "noise": 0.2}),
        ("UTampKitchen-v0", {"domain": "utamp1"}),
        ("UTampKitchenSlide-v0", {}),
        ("UTampKitchenProcedural-v0", {}),
    ],
)
def test_mask_and_vector_as_before_along_random_walks(env_id: str, options: dict) -> None:
    env = gym.make(env_id, grounding="symbolic", **options).unwrapped
    rng = np.random.default_rng(1)
    steps = 0
    for seed in range(6):
        obs, info = env.reset(seed=seed)
        for _ in range(30):
            state = env._state
            assert (state.applicable_mask() == reference_mask(state)).all()
            assert state.vector().dtype == np.int8
            assert (state.vector() == reference_vector(state)).all()
            if "symbolic" in obs:  # the objects interface observes otherwise
                assert (obs["symbolic"] == reference_vector(state)).all()
            valid = np.flatnonzero(info["action_mask"])
            if not len(valid):
                break
            obs, _, terminated, truncated, info = env.step(int(rng.choice(valid)))
            steps += 1
            if terminated or truncated:
                break
    assert steps > 60


@pytest.mark.parametrize("kept", [2, 4096])
def test_kept_symbolic_vectors_are_the_states_and_fresh_copies(
    kept: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The observation's ``symbolic`` vector comes from the `Observer`'s kept vectors (by the
    state's bits): along walks that revisit states (undone picks), and when the kept ones
    overflow (`VECTORS_KEPT` 2), it is the state's, and changing it changes no later one."""
    monkeypatch.setattr(observe, "VECTORS_KEPT", kept)
    env = UTampKitchenEnv(suite="pick-place", grounding="symbolic")
    rng = np.random.default_rng(4)
    seen: dict[int, int] = {}
    for seed in range(4):
        obs, info = env.reset(seed=seed)
        for _ in range(40):
            state = env._state
            assert (obs["symbolic"] == reference_vector(state)).all()
            seen[state.bits] = seen.get(state.bits, 0) + 1
            obs["symbolic"][:] = 7  # a caller's change stays in its copy
            valid = np.flatnonzero(info["action_mask"])
            obs, _, terminated, _, info = env.step(int(rng.choice(valid)))
            if terminated:
                break
    assert max(seen.values()) > 2  # states were revisited
    assert len(env._observation._vectors) <= kept
