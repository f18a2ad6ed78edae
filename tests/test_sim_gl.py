"""`utamp_gym.sim.gl`: MuJoCo renders headless with nothing set, on mujoco 3 and 4.

Runs in `make test-mujoco4` too (mujoco 4 keeps the context class where 3.17 does). Renders
happen in child processes with a headless user's environment (`procs.user_env`).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from procs import user_env

from utamp_gym.sim import gl

pytestmark = pytest.mark.physics


def _python(code: str, cwd: Path, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        cwd=cwd,
        env=user_env(**env),
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_renders_after_mujoco_was_imported_with_nothing_set(tmp_path: Path) -> None:
    """MuJoCo picked GLFW at its import (MUJOCO_GL unset, no display); `new_renderer` points
    its context class at the backend it chose, and the frame is real."""
    code = """
        import mujoco
        import numpy as np
        from utamp_gym.sim import gl

        xml = (
            "<mujoco><worldbody><light pos='0 0 2'/>"
            "<geom type='box' size='.2 .2 .2' rgba='1 0 0 1'/></worldbody></mujoco>"
        )
        model = mujoco.MjModel.from_xml_string(xml)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        renderer = gl.new_renderer(model, 32, 48)
        renderer.update_scene(data)
        frame = renderer.render()
        print(gl.ensure_gl(), frame.shape, int(frame[..., 0].max()))
    """
    run = _python(code, tmp_path)
    assert run.returncode == 0, run.stderr
    backend, *rest = run.stdout.split()
    assert backend in ("egl", "osmesa") and " ".join(rest[:3]) == "(32, 48, 3)"
    assert int(rest[3]) > 100  # the red box is in the picture


def test_an_explicit_mujoco_gl_is_used_without_probing(tmp_path: Path) -> None:
    code = """
        import logging, sys
        logging.basicConfig(stream=sys.stdout, level=logging.DEBUG, format="LOG %(message)s")
        from utamp_gym.sim import gl

        def no_probe(backend):
            raise AssertionError("probed although MUJOCO_GL is set")

        gl.probe = no_probe
        import mujoco
        r = gl.new_renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 8, 8)
        print("FRAME", r.render().shape)
    """
    run = _python(code, tmp_path, MUJOCO_GL="egl")
    assert run.returncode == 0, run.stderr
    assert "FRAME (8, 8, 3)" in run.stdout
    assert "LOG MuJoCo GL backend: egl (MUJOCO_GL is set)" in run.stdout


def test_no_working_backend_names_the_debian_packages(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(gl, "probe", lambda backend: f"no {backend} here")
    gl.ensure_gl.cache_clear()
    try:
        with pytest.raises(gl.NoGLBackendError) as err:
            gl.ensure_gl()
    finally:
        gl.ensure_gl.cache_clear()
    message = str(err.value)
    assert "egl: no egl here; osmesa: no osmesa here" in message
    assert "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri" in message
    assert "apt-get install libosmesa6" in message


def test_a_desktop_tries_glfw_first_a_server_egl_then_osmesa() -> None:
    assert gl.candidates({}) == ("egl", "osmesa")
    assert gl.candidates({"DISPLAY": ":0"}) == ("glfw", "egl", "osmesa")
    assert gl.candidates({"WAYLAND_DISPLAY": "wayland-0"})[0] == "glfw"
