"""The object-centric interface (``interface="objects"``): fixed spaces over object slots, a
lossless relational observation, an exact mask over parametrised macro actions, shuffled
slots, and the same episodes as the grounded interface."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from utamp_gym.agents import PlannerPolicy
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.object_maps import tables
from utamp_gym.env.objects import (
    GRASPS,
    MAX_OBJECTS,
    N_ACTIONS,
    ObjectAction,
    decode,
    encode,
    encode_type,
    member_order,
)
from utamp_gym.env.registry import register_envs
from utamp_gym.errors import UnknownNameError
from utamp_gym.suites.generate import EXTRA_MOVABLES, MOVABLES, TRAY

register_envs()
EXTRA_OBJECTS = [TRAY[0], *(n for n, _ in MOVABLES), *(n for n, _ in EXTRA_MOVABLES)]


def objects_env(env_id: str = "UTampKitchen-v0", **kw: object) -> gym.Env:
    return gym.make(env_id, grounding="symbolic", interface="objects", **kw)


def test_index_encoding_round_trips() -> None:
    assert len(GRASPS) == 24 and len(set(GRASPS)) == 24
    for index in range(N_ACTIONS):
        assert encode(decode(index)) == index
    with pytest.raises(ValueError):
        encode(ObjectAction("place", 0, member=1, support=2))
    with pytest.raises(ValueError):
        decode(N_ACTIONS)


@pytest.mark.parametrize("masks", ["affordances", "geometric", "none"])
@pytest.mark.parametrize("env_id", ["UTampKitchen-v0", "UTampKitchenSlide-v0"])
def test_check_env_and_one_space_for_every_suite(env_id: str, masks: str) -> None:
    env = objects_env(env_id, masks=masks)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.action_space == gym.spaces.Discrete(N_ACTIONS)
    reference = objects_env("UTampKitchen-v0")
    assert env.observation_space == reference.observation_space


def test_bad_interface_lists_the_valid_ones() -> None:
    with pytest.raises(UnknownNameError, match="grounded"):
        gym.make("UTampKitchen-v0", grounding="symbolic", interface="slots")


@pytest.mark.parametrize("masks", ["affordances", "geometric"])
def test_observation_is_lossless_and_the_mask_exact(masks: str) -> None:
    env = objects_env(masks=masks)
    kitchen = env.unwrapped
    assert isinstance(kitchen, UTampKitchenEnv) and kitchen.objects is not None
    rng = np.random.default_rng(0)
    for seed in range(15):
        obs, info = env.reset(seed=seed)
        oi = kitchen.objects
        atoms = tables(kitchen.universe.key).atoms
        for _ in range(8):
            # every fluent atom of the scene has its own cell (the empty hand: no object held)
            vec = kitchen._state.vector().astype(bool)
            pos = oi._atom_pos[vec]
            lost = [" ".join(atoms[j]) for j in np.flatnonzero(vec) if oi._atom_pos[j] < 0]
            assert lost in ([], ["oc in hand air"])
            assert len(set(pos[pos >= 0].tolist())) == int((pos >= 0).sum())
            cells = sum(int(obs[k].sum()) for k in ("held", "contact", "free", "in_workspace",
                                                    "member_in_workspace", "grasp"))  # fmt: skip
            assert cells == int((pos >= 0).sum())
            # every shown ground action has an index, and no two shown ones share it
            shown = np.flatnonzero(kitchen._state.mask())
            index = oi._index[shown]
            assert (index >= 0).all() and len(set(index.tolist())) == len(index)
            assert set(np.flatnonzero(info["action_mask"])) == set(index.tolist())
            allowed = np.flatnonzero(info["action_mask"])
            if not allowed.size:
                break
            obs, _, terminated, _, info = env.step(int(rng.choice(allowed)))
            if terminated:
                break


def test_slots_are_shuffled_by_the_env_rng() -> None:
    env = objects_env()
    kitchen = env.unwrapped
    seen = set()
    for seed in range(12):
        env.reset(seed=seed, options={"scene": "pick-place/105"})
        seen.add(kitchen.objects.slots["tray"])
        first = dict(kitchen.objects.slots)
        env.reset(seed=seed, options={"scene": "pick-place/105"})
        assert kitchen.objects.slots == first  # equal seeds: equal slots
    assert len(seen) >= 4
    obs, _ = env.reset(seed=0, options={"scene": "pick-place/000"})  # two objects
    assert int(obs["present"].sum()) == 2 and obs["present"].shape == (MAX_OBJECTS,)
    for name, slot in kitchen.objects.slots.items():
        assert np.allclose(obs["attributes"][slot], encode_type(kitchen.scene.type_of(name)))


def test_the_planner_acts_the_same_through_both_interfaces() -> None:
    """Equal seeds: the same scenes, and the planner's ground actions in the same order."""
    for masks in ("affordances", "geometric"):
        runs = []
        for interface in ("grounded", "objects"):
            env = gym.make("UTampKitchenSlide-v0", grounding="symbolic", masks=masks,
                           interface=interface)  # fmt: skip
            policy = PlannerPolicy(env)
            trace = []
            for seed in range(4):
                obs, info = env.reset(seed=seed)
                done = False
                while not done:
                    obs, reward, terminated, truncated, info = env.step(policy(obs, info))
                    trace.append((info["scene"], info["action"], float(reward)))
                    done = terminated or truncated
            runs.append(trace)
        assert runs[0] == runs[1]
        assert sum(r for *_, r in runs[0]) == 4.0


def test_an_index_without_a_ground_action_fails_without_change() -> None:
    env = objects_env()
    kitchen = env.unwrapped
    env.reset(seed=0, options={"scene": "pick-place/000"})
    empty = next(s for s in range(MAX_OBJECTS) if s not in kitchen.objects.slots.values())
    before = kitchen.true_atoms()
    index = encode(ObjectAction("pick", empty, 0, 0))
    _, reward, terminated, _, info = env.step(index)
    assert info["failure_reason"].startswith("no such action in scene pick-place/000: pick slot")
    assert kitchen.true_atoms() == before and not terminated and reward == 0.0
    with pytest.raises(ValueError):
        env.step(N_ACTIONS)


def test_extra_suite_and_pickling() -> None:
    env = UTampKitchenEnv(suite="extra", objects=EXTRA_OBJECTS, grounding="symbolic",
                          masks="geometric", interface="objects")  # fmt: skip
    obs, info = env.reset(seed=3)
    assert env.observation_space.contains(obs) and info["action_mask"].any()
    clone = pickle.loads(pickle.dumps(env))
    a = int(np.flatnonzero(info["action_mask"])[0])
    assert clone.step(a)[-1]["action"] == env.step(a)[-1]["action"]


def _meaning(kitchen: UTampKitchenEnv, text: str) -> dict[str, str]:
    """The PDDL arguments an `action_strings` entry names, read with this episode's slots."""
    where = {s: n for n, s in kitchen.objects.slots.items()}
    words = text.split()
    obj = where[int(words[1].removeprefix("slot"))]
    out = {"operator": f"{words[0]}-support", "object": obj}
    if "member" in words[2]:
        member = member_order(kitchen.scene.type_of(obj))[int(words[2].removeprefix("member"))]
        out["member"] = f"{obj}-{member}"
        out["grasp"] = " ".join(words[4].split("/"))
    if words[0] == "place":
        target = words[3]
        out["support"] = (
            where[int(target.removeprefix("slot"))] if target.startswith("slot")
            else kitchen.scene.slots[int(target.removeprefix("region"))].name
        )  # fmt: skip
    if words[0] == "slide":
        out["space"] = kitchen.scene.spaces[int(words[-1].removeprefix("space"))].name
    return out


def _pddl_meaning(action: str) -> dict[str, str]:
    """The same fields read from a ground action (a place also has the held member, grasp)."""
    name, *args = action[1:-1].split()
    out = {"operator": name, "object": args[0], "member": args[1], "grasp": " ".join(args[2:5])}
    if name == "place-support":
        out["support"] = args[8]
    if name == "slide-support":
        out["space"] = args[9]
    return out


@pytest.mark.parametrize(
    ("env_id", "masks"),
    [("UTampKitchenProcedural-v0", "affordances"), ("UTampKitchenProcedural-v0", "geometric"),
     ("UTampKitchenSlide-v0", "affordances")],
)  # fmt: skip
def test_action_strings_and_action_pddl_say_what_the_step_does(env_id: str, masks: str) -> None:
    """For every valid index along a few episodes: ``action_pddl(a)`` is the ``info["action"]``
    its step reports, and ``action_strings[a]`` names that action's object, member, grasp,
    support and space through the episode's slots."""
    env = gym.make(env_id, grounding="symbolic", interface="objects", masks=masks)
    kitchen = env.unwrapped
    assert len(kitchen.action_strings) == N_ACTIONS
    assert kitchen.action_strings[encode(ObjectAction("place", 3, support=MAX_OBJECTS + 1))] == (
        "place slot3 on region1"
    )
    rng = np.random.default_rng(1)
    checked = 0
    for seed in range(3):
        scene, prefix = env.reset(seed=seed)[1]["scene"], []
        _, info = env.reset(seed=seed, options={"scene": scene})  # as replayed below
        for _ in range(4):
            valid = np.flatnonzero(info["action_mask"])
            if not valid.size:
                break
            for a in rng.permutation(valid)[:15]:
                env.reset(seed=seed, options={"scene": scene})
                for p in prefix:
                    env.step(p)
                said = kitchen.action_pddl(int(a))
                meaning = _meaning(kitchen, kitchen.action_strings[a])
                *_, step_info = env.step(int(a))
                assert step_info["action"] == said != ""
                pddl = _pddl_meaning(said)
                assert {k: pddl.get(k) for k in meaning} == meaning
                checked += 1
            env.reset(seed=seed, options={"scene": scene})
            for p in prefix:
                env.step(p)
            a = int(rng.choice(valid))
            prefix.append(a)
            *_, terminated, _, info = env.step(a)
            if terminated:
                break
    assert checked >= 30  # indices checked (45 for the first case when written)
    # an index without a ground action here: "" (its step fails with "no such action")
    env.reset(seed=0, options={"scene": scene})
    empty = next(s for s in range(MAX_OBJECTS) if s not in kitchen.objects.slots.values())
    assert kitchen.action_pddl(encode(ObjectAction("pick", empty, 0, 0))) == ""


def test_grounded_action_strings_are_the_pddl_actions() -> None:
    env = gym.make("UTampKitchenProcedural-v0", grounding="symbolic", interface="grounded")
    kitchen = env.unwrapped
    assert kitchen.action_strings == kitchen.universe.actions
    _, info = env.reset(seed=0)
    a = int(np.flatnonzero(info["action_mask"])[0])
    assert kitchen.action_pddl(a) == kitchen.action_strings[a] == env.step(a)[-1]["action"]
