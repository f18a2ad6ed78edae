"""Minari's own `DataCollector(env, record_infos=True)` records episodes of every env id: the
info dict keeps one structure of numbers, bools and strings (`utamp_gym.env.info`)."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from utamp_gym.env.info import TIMING_KEYS, split_atoms
from utamp_gym.env.registry import env_ids, register_envs

minari = pytest.importorskip("minari")
pytest.importorskip("jax", reason="Minari's DataCollector needs minari[create] (jax)")

register_envs()

# these datasets are scratch files: the metadata Minari asks for (author, description, ...)
# would only be noise here (`utamp demos` writes it: `utamp_gym.data.minari_io`)
pytestmark = pytest.mark.filterwarnings(
    r"ignore:`(author|author_email|code_permalink|description|eval_env|algorithm_name)` is set to "
    r"None:UserWarning"
)


def _collect(env: gym.Env, episodes: int, seed: int, steps: int = 12) -> None:
    """Random masked episodes of at most `steps` steps: a longer one is cut by the next
    reset, which the collector records as a truncation. (Not by the env's TimeLimit: importing
    rl_zoo3 anywhere in the process replaces Gymnasium's TimeLimit by one that adds an info key
    on the last step only, which no dataset writer can stack.)"""
    rng = np.random.default_rng(seed)
    for episode in range(episodes):
        _, info = env.reset(seed=seed + episode)
        for _ in range(steps):
            allowed = np.flatnonzero(info["action_mask"])
            action = int(rng.choice(allowed)) if allowed.size else 0
            _, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
    env.reset(seed=seed + episodes)  # the last episode is written on this reset


@pytest.mark.parametrize("env_id", env_ids())
def test_data_collector_records_infos_of_every_env_id(
    env_id: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from minari import DataCollector

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    env = DataCollector(
        gym.make(env_id, grounding="symbolic", masks="geometric"),
        record_infos=True,
    )
    _collect(env, episodes=3, seed=0)
    name = env_id.lower().replace("-v0", "")
    env.create_dataset(dataset_id=f"utamp/{name}-random-v0", algorithm_name="random")
    env.close()
    data = minari.load_dataset(f"utamp/{name}-random-v0")
    assert data.total_episodes == 3
    for ep in data.iterate_episodes():
        n = len(ep.actions)
        infos = ep.infos
        assert infos["action_mask"].shape[0] == n + 1  # the reset's info, then every step's
        assert infos["action"][0] == b"" and all(infos["action"][1:])
        assert infos["macro_result"]["executed"].shape == (n + 1,)
        # every object of the scene, without an anomaly in symbolic grounding
        assert infos["anomalies"] and all((v == b"").all() for v in infos["anomalies"].values())
        assert len(set(infos["scene"])) == 1


def test_data_collector_records_the_objects_interface(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from minari import DataCollector

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    env = DataCollector(
        gym.make("UTampKitchenSlide-v0", grounding="symbolic", interface="objects",
                 masks="geometric"),
        record_infos=True,
    )  # fmt: skip
    _collect(env, episodes=2, seed=3, steps=8)
    env.create_dataset(dataset_id="utamp/slide-objects-v0", algorithm_name="random")
    space = env.observation_space
    env.close()
    for ep in minari.load_dataset("utamp/slide-objects-v0").iterate_episodes():
        assert ep.observations["contact"].shape[1:] == space["contact"].shape
        assert all(space.contains({k: v[t] for k, v in ep.observations.items()})
                   for t in range(len(ep.actions) + 1))  # fmt: skip


@pytest.mark.physics
def test_data_collector_records_physics_infos_with_timings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("utamp_gym.sim.backend", reason="the MuJoCo backend is not available")
    from minari import DataCollector

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    env = DataCollector(
        gym.make("UTampKitchen-v0", scene="pick-place/000", record_timings=True),
        record_infos=True,
    )  # fmt: skip
    _collect(env, episodes=1, seed=0, steps=2)
    env.create_dataset(dataset_id="utamp/kitchen-physics-v0")
    env.close()
    ep = next(minari.load_dataset("utamp/kitchen-physics-v0").iterate_episodes())
    timings = ep.infos["timings"]
    assert set(timings) == set(TIMING_KEYS)
    assert timings["step_s"][0] == 0.0 and (timings["step_s"][1:] > 0).all()
    assert ep.infos["macro_result"]["executed"][1:].all()
    for text in ep.infos["unexpected_atoms"]:
        assert all(a[0] in "+-" and a[1] == "(" for a in split_atoms(text.decode()))


def test_split_atoms_inverts_the_joined_string() -> None:
    from utamp_gym.env.info import join_atoms

    atoms = ["+(oc under salt tray)", "-(oc on tray salt)", "-(force salt on)"]
    assert split_atoms(join_atoms(atoms)) == atoms
    assert split_atoms("") == []
