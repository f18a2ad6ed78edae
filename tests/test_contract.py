"""The contract between the simulator and perception (issue "One episode engine", item 3):
the types both use live below both, the simulator fits no poses, and everything the env and
the evaluation ask of a backend is in `PhysicsBackend` and, for the cameras, `Surveying`."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import numpy as np
import pytest

import utamp_gym
from utamp_gym.backend import PERCEPTION_MODES, PhysicsBackend, Surveying
from utamp_gym.contract.views import ViewBundle
from utamp_gym.errors import UnknownNameError

ROOT = Path(utamp_gym.__file__).parent


def _imports(path: Path) -> set[str]:
    """Every module a file imports, at the top or inside a function."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_the_simulator_and_the_contract_never_import_perception() -> None:
    files = [*sorted((ROOT / "sim").glob("*.py")), *(ROOT / "contract").glob("*.py")]
    for path in [*files, ROOT / "backend.py"]:
        bad = [m for m in _imports(path) if m.startswith("utamp_gym.perception")]
        assert not bad, (path.name, bad)


def test_the_contract_sits_below_the_simulator_and_perception() -> None:
    allowed = ("utamp_gym.contract", "utamp_gym.scene", "numpy", "__future__")
    for path in (ROOT / "contract").glob("*.py"):
        own = {m for m in _imports(path) if m.split(".")[0] in ("utamp_gym", "numpy")}
        assert all(m.startswith(allowed) for m in own), (path.name, own)


def test_the_simulator_takes_a_pose_tracking_not_a_name() -> None:
    from utamp_gym.grounding import TRACKING, physics_backend
    from utamp_gym.perception.tracking import rgbd_tracking
    from utamp_gym.sim.backend import MujocoBackend

    with pytest.raises(ValueError, match=r"physics_backend\(perception='rgbd'\)"):
        MujocoBackend(perception="rgbd")
    assert tuple(TRACKING) == PERCEPTION_MODES
    assert physics_backend(perception="rgbd").tracking is rgbd_tracking
    assert physics_backend().tracking is None
    with pytest.raises(UnknownNameError, match="rgbd"):
        physics_backend(perception="rgb")


def test_a_backend_without_cameras_is_a_backend_that_cannot_survey() -> None:
    class Blind:
        def reset(self, scene, rng) -> None: ...
        def execute(self, action): ...
        def physical_state(self): ...
        def object_poses(self) -> dict:
            return {}

        def joint_positions(self) -> np.ndarray:
            return np.zeros(9)

        def stacked_on_tray(self) -> list:
            return []

        def render(self, width: int, height: int) -> np.ndarray:
            return np.zeros((1, 1, 3))

        def close(self) -> None: ...

    class Seeing(Blind):
        cameras = None

        def survey(self) -> ViewBundle:
            return ViewBundle(())

    assert isinstance(Blind(), PhysicsBackend) and not isinstance(Blind(), Surveying)
    assert isinstance(Seeing(), PhysicsBackend) and isinstance(Seeing(), Surveying)


@pytest.mark.parametrize(("old", "new", "name"), [
    ("utamp_gym.perception.state", "utamp_gym.contract.state", "PhysicalState"),
    ("utamp_gym.perception.views", "utamp_gym.contract.views", "ViewBundle"),
    ("utamp_gym.planning.methods", "utamp_gym.affordances.sources", "ground_truth_for"),
    ("utamp_gym.env.scene_cache", "utamp_gym.symbolic.scene_cache", "SceneCache"),
    ("utamp_gym.env.outcome", "utamp_gym.symbolic.outcome", "OutcomeModel"),
    ("utamp_gym.env.universe_store", "utamp_gym.symbolic.universe_store", "load"),
    ("utamp_gym.env.dm_adapter", "utamp_gym.dm.adapter", "DmEnvAdapter"),
    ("utamp_gym.eval.vlm_methods", "utamp_gym.methods.vlm", "run_vlm_planner"),
    ("utamp_gym.eval.vlm_client", "utamp_gym.methods.vlm_client", "VlmClient"),
    ("utamp_gym.eval.perceived", "utamp_gym.methods.perceived", "attribute_accuracy"),
])  # fmt: skip
def test_a_moved_name_still_imports_from_its_old_path_with_a_warning(
    old: str, new: str, name: str
) -> None:
    import importlib

    module = importlib.import_module(old)
    with pytest.warns(DeprecationWarning, match=f"{old}.{name} moved to {new}.{name}"):
        value = getattr(module, name)
    assert value is getattr(sys.modules[new], name)
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        module.Nope  # noqa: B018
