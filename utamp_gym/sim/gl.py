"""OpenGL for MuJoCo's offscreen rendering: a working backend, chosen before GL is first used.

Why: MuJoCo fixes its GL backend when ``mujoco`` is imported (``MUJOCO_GL``; unset means GLFW,
which needs a display), so on a headless server every frame failed until the user guessed
``MUJOCO_GL=egl``. Every renderer of this package is made by `new_renderer` (or calls
`ensure_gl` first), which settles the backend once per process:

* ``MUJOCO_GL`` set: respected as it is (MuJoCo's own values: glfw, egl, osmesa, ...).
* unset, on Linux: the first backend that renders a frame in a short probe subprocess (a
  failed GL start can abort a process, so never in this one): GLFW first when a display is
  set (``DISPLAY`` or ``WAYLAND_DISPLAY``: a desktop keeps MuJoCo's default), then EGL, then
  OSMesa. None works: `NoGLBackendError` names the Debian packages to install.
* unset, elsewhere (macOS, Windows): MuJoCo's default (CGL, WGL / GLFW need no setting).

The choice is written to ``os.environ["MUJOCO_GL"]`` (child processes and dm_control, which
reads it on import, agree without probing again). If ``mujoco`` was imported before the choice,
its context class is pointed at the chosen backend's
(``mujoco.rendering.classic.gl_context.GLContext`` in mujoco 3.17 and 4.0), since setting the
variable after ``import mujoco`` changes nothing (`ensure_dm_control_gl` does the same for
dm_control's renderer; `utamp_gym.dm` settles the backend before it imports dm_control). The
choice is logged in one debug line (logger ``utamp_gym.sim.gl``). The ``human`` viewer
(`mujoco.viewer`) opens its own GLFW window and does not depend on this choice.
"""

from __future__ import annotations

import functools
import importlib
import logging
import os
import subprocess
import sys
import time
from typing import Any

from utamp_gym.errors import UtampError

logger = logging.getLogger(__name__)

#: what each headless backend needs on Debian / Ubuntu (``apt-get install ...``)
DEBIAN_PACKAGES: dict[str, tuple[str, ...]] = {
    "egl": ("libegl1", "libegl-mesa0", "libgl1-mesa-dri"),
    "osmesa": ("libosmesa6",),
    "glfw": ("libglfw3", "libgl1"),
}
HEADLESS = ("egl", "osmesa")
PROBE_TIMEOUT_S = 60.0
#: renders one frame of an empty model with the backend named by MUJOCO_GL
_PROBE = (
    "import mujoco\n"
    "m = mujoco.MjModel.from_xml_string('<mujoco/>')\n"
    "r = mujoco.Renderer(m, 8, 8)\n"
    "r.render()\n"
    "r.close()\n"
)


class NoGLBackendError(UtampError, RuntimeError):
    """No OpenGL backend can render MuJoCo frames in this process; says what to install."""


def candidates(environ: dict[str, str] | None = None) -> tuple[str, ...]:
    """Backends tried, in order, when ``MUJOCO_GL`` is unset (Linux; module docstring)."""
    env = os.environ if environ is None else environ
    desktop = bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))
    return (("glfw",) if desktop else ()) + HEADLESS


@functools.cache
def ensure_gl() -> str:
    """The GL backend MuJoCo renders with in this process; chosen and installed on first call.

    Raises `NoGLBackendError` when ``MUJOCO_GL`` is unset and no backend works.
    """
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    if requested:
        _install(requested)
        logger.debug("MuJoCo GL backend: %s (MUJOCO_GL is set)", requested)
        return requested
    if not sys.platform.startswith("linux"):
        logger.debug("MuJoCo GL backend: MuJoCo's default on %s (MUJOCO_GL is unset)", sys.platform)
        return "default"
    start = time.perf_counter()
    tried = candidates()
    failures: dict[str, str] = {}
    for backend in tried:
        why = probe(backend)
        if why is None:
            os.environ["MUJOCO_GL"] = backend
            _install(backend)
            logger.debug(
                "MuJoCo GL backend: %s (MUJOCO_GL was unset; tried %s; probed in %.2f s)",
                backend,
                ", ".join(tried[: tried.index(backend) + 1]),
                time.perf_counter() - start,
            )
            return backend
        failures[backend] = why
    raise NoGLBackendError(install_hint(failures))


def install_hint(failures: dict[str, str]) -> str:
    """The message of `NoGLBackendError`: what failed and the packages that fix it."""
    tried = "; ".join(f"{b}: {why}" for b, why in failures.items())
    egl, osmesa = (" ".join(DEBIAN_PACKAGES[b]) for b in HEADLESS)
    return (
        f"MuJoCo cannot render: no OpenGL backend works in this process (tried {tried}). "
        f"Install a headless one (Debian/Ubuntu): apt-get install {egl} (EGL, preferred) "
        f"or apt-get install {osmesa} (OSMesa); or set MUJOCO_GL to a backend that works here"
    )


def probe(backend: str) -> str | None:
    """None if `backend` renders a frame in a fresh Python process, else why not (one line)."""
    env = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"}
    env["MUJOCO_GL"] = backend
    try:
        done = subprocess.run(
            [sys.executable, "-c", _PROBE],
            env=env,
            capture_output=True,
            text=True,
            timeout=PROBE_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return f"no frame within {PROBE_TIMEOUT_S:.0f} s"
    if done.returncode == 0:
        return None
    lines = [line.strip() for line in done.stderr.splitlines() if line.strip()]
    return lines[-1] if lines else f"exit code {done.returncode}"


def new_renderer(model: Any, height: int, width: int) -> Any:
    """A `mujoco.Renderer` of `model`, on the backend `ensure_gl` chose."""
    ensure_gl()
    import mujoco

    return mujoco.Renderer(model, height, width)


def _install(backend: str) -> None:
    """Point an already-imported MuJoCo renderer at `backend`'s context."""
    if "mujoco" in sys.modules:
        _install_mujoco(backend)


def ensure_dm_control_gl() -> str:
    """`ensure_gl` for dm_control's renderer too (it read ``MUJOCO_GL`` when it was imported);
    called before dm_control makes its first GL context."""
    backend = ensure_gl()
    render = sys.modules.get("dm_control._render")
    importer = {"glfw": "_import_glfw", "egl": "_import_egl", "osmesa": "_import_osmesa"}
    if render is not None and backend in importer and getattr(render, "BACKEND", None) != backend:
        render.Renderer = getattr(render, importer[backend])()
        render.BACKEND = backend
        render.USING_GPU = backend in ("egl", "glfw")
    return backend


def _install_mujoco(backend: str) -> None:
    """Set MuJoCo's context class to `backend`'s unless it already is (mujoco 3.17, 4.0)."""
    if backend not in ("glfw", "egl", "osmesa"):
        return  # MuJoCo's other values (disable, cgl, wgl, ...) are its own business
    module = None
    for name in ("mujoco.rendering.classic.gl_context", "mujoco.gl_context"):
        try:
            module = importlib.import_module(name)
            break
        except ImportError:
            continue
    current = getattr(module, "GLContext", None)
    wanted = f"mujoco.{backend}"
    if module is None or getattr(current, "__module__", None) == wanted:
        return
    context = importlib.import_module(wanted).GLContext
    module.GLContext = context
    mujoco = sys.modules["mujoco"]
    if hasattr(mujoco, "GLContext"):
        mujoco.GLContext = context
    legacy = sys.modules.get("mujoco.gl_context")
    if legacy is not None and legacy is not module:
        legacy.GLContext = context
