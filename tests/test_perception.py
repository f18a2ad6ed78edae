"""Perception: symbolic atoms from a physical state (pure: no simulator needed).

A scripted backend feeds the env physical states, so the closed loop (perceived state, mask,
execution monitoring, termination) is tested here without MuJoCo; `test_closed_loop.py`
runs the same against the MuJoCo backend.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from utamp_gym.backend import MacroResult, PhysicsBackend
from utamp_gym.contract.state import FLOOR, TABLE, Grasp, PhysicalState
from utamp_gym.contract.views import ViewBundle
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.env.physics import perceived_static, unexpected_atoms
from utamp_gym.perception.abstraction import declared_state, perceive
from utamp_gym.scene.model import Scene
from utamp_gym.suites import resolve_scene, suite_scenes
from utamp_gym.symbolic.problem import scene_facts

GEOMETRIC = ("(oc ", "(force ", "(base ", "(isgraspfrom ")
SIDE_UP = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)  # a quarter turn about x


def geometric_facts(scene: Scene) -> frozenset[str]:
    """The problem generator's atoms that perception must reproduce."""
    return frozenset(f.lower() for f in scene_facts(scene, ()) if f.lower().startswith(GEOMETRIC))


@pytest.mark.parametrize("suite", ["pick-place", "sliding"])
def test_the_declared_state_perceives_as_the_scene_initial_state(suite: str) -> None:
    for scene in suite_scenes(suite):
        perception = perceive(scene, declared_state(scene))
        assert perception.atoms == geometric_facts(scene), scene.name
        assert perception.anomalies == {}


def _moved(state: PhysicalState, name: str, **changes: object) -> PhysicalState:
    """A copy of `state` with `name`'s support, on_top flag or pose changed."""
    supports, on_top, poses = dict(state.supports), dict(state.on_top), dict(state.poses)
    if "support" in changes:
        supports[name] = changes["support"]  # type: ignore[assignment]
    if "on_top" in changes:
        on_top[name] = bool(changes["on_top"])
    if "quat" in changes:
        poses[name] = (*poses[name][:3], *changes["quat"])  # type: ignore[misc]
    return replace(state, supports=supports, on_top=on_top, poses=poses)


@pytest.fixture(scope="module")
def demo() -> Scene:
    return resolve_scene("kitchen-demo")  # salt on slot5 beside an inverted mug on slot4


def _own_atoms(atoms: frozenset[str], name: str) -> set[str]:
    """Atoms about `name`'s own parts or members (not other objects' atoms mentioning it)."""
    out = set()
    for atom in atoms:
        words = atom.strip("()").split()
        if words[0] == "oc" and words[1:3] == ["in", "workspace"]:
            mine = words[3] == name or words[3].startswith(f"{name}-")
        elif words[0] == "oc":
            mine = words[2] == name
        else:
            mine = words[1] == name
        if mine:
            out.add(atom)
    return out


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"support": FLOOR}, "salt fell off the table"),
        ({"support": TABLE}, "salt lies on the table outside every slot"),
        ({"support": None}, "salt rests on nothing"),
        ({"quat": SIDE_UP}, "salt toppled over: its left side faces up"),
    ],
)
def test_an_object_without_a_symbol_has_no_atoms_of_its_own(demo, change, reason) -> None:
    state = _moved(declared_state(demo), "salt", **change)
    perception = perceive(demo, state)
    assert perception.anomalies["salt"].startswith(reason)
    assert _own_atoms(perception.atoms, "salt") == set()
    assert "salt" not in perception.supports
    # its slot stays occupied by it when it is still there (toppled in place), else it is free
    occupied = "(oc on slot5 salt)" in perception.fluent
    assert occupied == (change.get("support", "slot5") == "slot5")


def test_an_object_resting_inside_another_is_not_on_it(demo) -> None:
    # the shaker dropped into a (hypothetical) upright container: containment is not support
    state = _moved(declared_state(demo), "salt", support="mug", on_top=False)
    perception = perceive(demo, state)
    assert "containment is not support" in perception.anomalies["salt"]
    assert "(oc under mug salt)" in perception.fluent  # the mug's up part is occupied
    assert "(oc under mug air)" not in perception.fluent
    assert _own_atoms(perception.atoms, "salt") == set()


def test_an_object_on_a_lost_one_is_lost_too(demo) -> None:
    state = declared_state(demo)
    state = _moved(state, "salt", support="mug")  # salt on the inverted mug ...
    state = _moved(state, "mug", quat=SIDE_UP)  # ... which toppled
    perception = perceive(demo, state)
    assert set(perception.anomalies) == {"mug", "salt"}
    assert "which has no symbol" in perception.anomalies["salt"]


def test_the_held_object_and_its_grasp() -> None:
    scene = resolve_scene("pick-place/017")  # salt on slot2, board on the tray
    state = declared_state(scene)
    grasp = Grasp("salt", "body", "on", "front", "back")
    held = replace(_moved(state, "salt", support=None), held=grasp)
    perception = perceive(scene, held)
    assert perception.held == "salt" and perception.anomalies == {}
    assert {"(oc in hand salt)", "(isgraspfrom salt salt-body on front back)",
            "(oc under salt air)", "(oc on slot2 air)"} <= perception.fluent  # fmt: skip
    assert "(force salt on)" in perception.orientation


def test_execution_monitoring_and_perceived_static() -> None:
    assert unexpected_atoms({"(a)", "(b)"}, {"(b)", "(c)"}) == ["+(c)", "-(a)"]
    assert unexpected_atoms({"(a)"}, {"(a)"}) == []
    scene = resolve_scene("kitchen-demo")
    toppled = perceive(scene, _moved(declared_state(scene), "salt", quat=SIDE_UP))
    static = perceived_static(frozenset({"(force salt on)", "(canlift salt salt-body)"}), toppled)
    assert "(canlift salt salt-body)" in static and "(force salt on)" not in static


# ------------------------------------------------------------------ the env's closed loop
class ScriptedBackend:
    """A physics backend whose physical state after each action is scripted by the test."""

    def __init__(self, *, pose_noise: float = 0.0) -> None:
        self.scene: Scene | None = None
        self.next_state: PhysicalState | None = None
        self.executed: list[str] = []

    def reset(self, scene: Scene, rng: np.random.Generator) -> None:
        self.scene, self.next_state, self.executed = scene, declared_state(scene), []

    def execute(self, action: str) -> MacroResult:
        self.executed.append(action)
        return MacroResult(True, None, {})

    def physical_state(self) -> PhysicalState:
        assert self.next_state is not None
        return self.next_state

    def object_poses(self) -> dict[str, np.ndarray]:
        assert self.next_state is not None
        return {n: np.asarray(p) for n, p in self.next_state.poses.items()}

    def joint_positions(self) -> np.ndarray:
        return np.zeros(9)

    def stacked_on_tray(self) -> list[str]:
        return []

    def render(self, width: int, height: int) -> np.ndarray:
        return np.zeros((height, width, 3), np.uint8)

    def survey(self) -> ViewBundle:
        return ViewBundle(())  # no cameras: nothing seen

    @property
    def cameras(self) -> ScriptedBackend:
        return self

    @property
    def instances(self) -> dict[int, str]:
        return {}

    def close(self) -> None:
        pass


def test_the_env_mask_follows_the_perceived_state() -> None:
    env = UTampKitchenEnv(
        suite="pick-place", scene="pick-place/017", grounding="physics", backend=ScriptedBackend
    )
    backend = env.backend
    assert isinstance(backend, ScriptedBackend) and isinstance(backend, PhysicsBackend)
    obs, info = env.reset(seed=0)
    pick = env.universe.index("(pick-support salt salt-body on front back back on slot2 under on)")
    assert info["action_mask"][pick] and info["unexpected_atoms"] == ""
    # the pick "succeeds", but the world says the shaker fell off the table
    scene = resolve_scene("pick-place/017")
    backend.next_state = _moved(declared_state(scene), "salt", support=FLOOR)
    obs, reward, terminated, _, info = env.step(pick)
    assert backend.executed == [env.action_strings[pick]]
    assert {k: v for k, v in info["anomalies"].items() if v} == {"salt": "salt fell off the table"}
    assert "-(oc in hand salt)" in info["unexpected_atoms"]
    assert "-(force salt on)" in info["unexpected_atoms"]
    assert "(oc on slot2 air)" in env.true_atoms() and "(oc in hand air)" in env.true_atoms()
    assert not any("salt" in env.action_strings[a] for a in np.flatnonzero(info["action_mask"]))
    assert terminated and reward == 0.0  # the goal can no longer be reached
    on_floor = {a for j, a in enumerate(env.symbolic_atoms) if obs["symbolic"][j]}
    assert "(oc in hand salt)" not in {a.lower() for a in on_floor}
    env.close()


def test_the_env_reports_nothing_unexpected_when_the_world_agrees() -> None:
    env = UTampKitchenEnv(
        suite="pick-place", scene="pick-place/017", grounding="physics", backend=ScriptedBackend
    )
    backend = env.backend
    assert isinstance(backend, ScriptedBackend)
    env.reset(seed=0)
    pick = env.universe.index("(pick-support salt salt-body on front back back on slot2 under on)")
    scene = resolve_scene("pick-place/017")
    grasp = Grasp("salt", "body", "on", "front", "back")
    backend.next_state = replace(_moved(declared_state(scene), "salt", support=None), held=grasp)
    _, reward, terminated, _, info = env.step(pick)
    assert info["unexpected_atoms"] == "" and not any(info["anomalies"].values())
    assert not terminated and reward == 0.0
    assert "(oc in hand salt)" in env.true_atoms()
    env.close()
