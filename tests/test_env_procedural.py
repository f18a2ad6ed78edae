"""UTampKitchenProcedural-v0: every split through gymnasium's checker, in both groundings.

The generic env tests (tests/test_env.py, tests/test_env_tools.py) run this id with its
default split too; here each split, the option's validation and the shared action space.
"""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from utamp_gym.env.registry import register_envs
from utamp_gym.errors import UnknownNameError
from utamp_gym.suites import procedural

ENV_ID = "UTampKitchenProcedural-v0"
SPLITS = procedural.SPLITS


@pytest.fixture(scope="module", autouse=True)
def _registered() -> None:
    register_envs()


@pytest.mark.parametrize("interface", ["objects", "grounded"])
@pytest.mark.parametrize("split", SPLITS)
def test_check_env_symbolic(
    split: str, interface: str, session_display: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    env = gym.make(
        ENV_ID, split=split, interface=interface, grounding="symbolic", render_mode="rgb_array"
    )
    if session_display is not None:
        monkeypatch.setenv("DISPLAY", session_display.name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the checker's warnings count as failures
        check_env(env.unwrapped, skip_render_check=session_display is None)
    env.close()


@pytest.mark.physics
@pytest.mark.slow  # as tests/test_env_physics.py for the other ids
@pytest.mark.parametrize("split", SPLITS)
def test_check_env_physics(split: str, session_display: Any, monkeypatch) -> None:
    # wall-clock timings would differ between the checker's two identical runs
    env = gym.make(ENV_ID, split=split, num_objects=2 if split != "test-count" else 6,
                   record_timings=False)  # fmt: skip
    if session_display is not None:
        monkeypatch.setenv("DISPLAY", session_display.name)
    check_env(env.unwrapped, skip_render_check=session_display is None)
    env.close()


def test_every_split_shares_the_action_space_and_rows() -> None:
    assert gym.spec(ENV_ID).kwargs["interface"] == "objects"  # #24's default for this id
    envs = [
        gym.make(ENV_ID, split=s, grounding="symbolic", interface="grounded").unwrapped
        for s in SPLITS
    ]
    assert len({e.universe for e in envs}) == 1
    assert all(e.options.objects == procedural.OBJECT_NAMES for e in envs)
    for env, split in zip(envs, SPLITS, strict=True):
        assert {s.name for s in env.scenes} == set(
            f"procedural-v1/{split}/{i:04d}" for i in range(len(procedural.split_seeds(split)))
        )
        _, info = env.reset(seed=0)
        assert info["scene"].startswith(f"procedural-v1/{split}/")
        assert np.any(info["action_mask"])


def test_split_option_is_validated() -> None:
    with pytest.raises(UnknownNameError, match="test-count, test-families, test-instances"):
        gym.make(ENV_ID, split="validation")
    with pytest.raises(ValueError, match="drop suite"):
        gym.make(ENV_ID, split="train", suite="pick-place")
    env = gym.make(ENV_ID, split="procedural-v1/test-count", grounding="symbolic")
    assert env.unwrapped.options.split == "test-count"
    assert {s.n_objects for s in env.unwrapped.scenes} == {6}
