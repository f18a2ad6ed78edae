"""The render modes of the kitchen envs: frames for ``render()`` and the ``human`` windows.

* ``"rgb_array"``: ``render()`` returns the current frame (the simulator's overview camera in
  physics grounding, the labelled schematic of `utamp_gym.env.render` in symbolic grounding).
* ``"rgb_array_list"`` (Gymnasium's convention): ``render()`` returns every frame rendered
  since the last ``render()`` call or ``reset()``, then forgets them. In physics grounding a
  frame is rendered every 1/`FRAME_RATE` s of *simulated* time while a macro action runs
  (`MujocoBackend.watch`), plus one after reset and after every step, so a macro action of
  4 s gives about 40 frames; in symbolic grounding one frame per step.
* ``"human"``: in physics grounding a live MuJoCo viewer (`mujoco.viewer.launch_passive`)
  on the simulator's model, synced `HUMAN_SYNC_HZ` times per simulated second while actions
  run and paced to real time; in symbolic grounding a matplotlib window with the labelled
  schematic, redrawn after every step (at most `SYMBOLIC_HUMAN_FPS` steps per second).
  Both need a display: without one the env raises `NoDisplayError` when it is made.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from utamp_gym.env.render import LabelledSchematic
from utamp_gym.errors import UtampError
from utamp_gym.scene.model import Scene

FRAME_RATE = 10  # frames per simulated second in "rgb_array_list" (physics grounding)
STEP_RATE = 2  # nominal frames per second when there is one frame per macro action
HUMAN_SYNC_HZ = 30  # viewer syncs per simulated second while a macro action runs
SYMBOLIC_HUMAN_FPS = 2  # steps per second shown by the symbolic window
WINDOW_JOIN_S = 10.0  # s to wait for a closed viewer's thread
#: the viewer's initial free camera: looking at the table from the side facing the robot
LOOKAT, DISTANCE, AZIMUTH, ELEVATION = (0.45, 0.0, 0.1), 1.9, 180.0, -35.0


def aim_camera(camera: Any) -> None:
    """Point a MuJoCo viewer's free camera (`mujoco.MjvCamera`) at the table."""
    camera.lookat[:] = LOOKAT
    camera.distance, camera.azimuth, camera.elevation = DISTANCE, AZIMUTH, ELEVATION


class NoDisplayError(UtampError, RuntimeError):
    """``render_mode="human"`` (or ``utamp view``) without a display to open a window on."""


class LiveSimulation(Protocol):
    """A backend whose live MuJoCo state can be watched while actions run (`MujocoBackend`)."""

    @property
    def model(self) -> Any: ...

    @property
    def data(self) -> Any: ...

    def watch(self, callback: Callable[[], None], period: float) -> Callable[[], None]: ...


def is_live(backend: object | None) -> bool:
    """True if `backend` implements `LiveSimulation` (checked on its class: the live model
    exists only after a reset)."""
    return backend is not None and all(
        hasattr(type(backend), a) for a in ("model", "data", "watch")
    )


def require_display(what: str, instead: str) -> None:
    """Raise `NoDisplayError` naming `what` and the headless alternative `instead` unless a
    window can be opened (Linux: DISPLAY or WAYLAND_DISPLAY is set)."""
    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        raise NoDisplayError(
            f"{what} needs a display, and DISPLAY is not set; run it in a desktop session or "
            f"under a virtual display (xvfb-run), or use {instead}"
        )


class MujocoWindow:
    """A passive MuJoCo viewer on a live model; reopened when the model changes (reset)."""

    def __init__(self) -> None:
        self._handle: Any = None
        self._thread: threading.Thread | None = None
        self._model: Any = None

    def show(self, model: Any, data: Any) -> None:
        """Show `data` (open the window first, or again for a new model)."""
        if model is not self._model:
            self.close()
            import mujoco.viewer

            before = set(threading.enumerate())
            self._handle = mujoco.viewer.launch_passive(
                model, data, show_left_ui=False, show_right_ui=False
            )
            new = [t for t in threading.enumerate() if t not in before]
            self._thread = new[0] if new else None
            self._model = model
            with self._handle.lock():
                aim_camera(self._handle.cam)
        self.sync()

    def sync(self) -> None:
        if self._handle is not None and self._handle.is_running():
            self._handle.sync()

    @property
    def is_open(self) -> bool:
        return self._handle is not None and self._handle.is_running()

    def close(self) -> None:
        """Close the window and wait for its thread (a thread left running crashes the exit)."""
        if self._handle is not None:
            self._handle.close()
            if self._thread is not None:
                self._thread.join(WINDOW_JOIN_S)
        self._handle, self._thread, self._model = None, None, None


class SchematicWindow:
    """A Tk window with a matplotlib canvas, redrawn by a ``draw(axes)`` callable.

    Tk directly rather than pyplot: pyplot's backend is process-global (a module may have
    chosen Agg), a window of our own is not.
    """

    def __init__(self, title: str) -> None:
        self.title = title
        self._root: Any = None
        self._figure: Any = None
        self._canvas: Any = None
        self._closed = False

    def _open(self) -> None:
        try:
            import tkinter

            from matplotlib.backends.backend_tkagg import FigureCanvasTkAgg
            from matplotlib.figure import Figure
        except ImportError as exc:
            raise NoDisplayError(f"a schematic window needs tkinter ({exc})") from exc
        try:
            self._root = tkinter.Tk(className="utamp")
        except tkinter.TclError as exc:
            raise NoDisplayError(f"cannot open a window: {exc}") from exc
        self._root.title(self.title)
        self._root.protocol("WM_DELETE_WINDOW", self.close)
        self._figure = Figure(figsize=(6.0, 6.0), dpi=100)
        self._canvas = FigureCanvasTkAgg(self._figure, master=self._root)
        self._canvas.get_tk_widget().pack(fill="both", expand=True)

    def show(self, draw: Callable[[Any], None], pause: float) -> None:
        """Redraw, then keep the window responsive for `pause` seconds."""
        if self._closed:
            return  # closed by the user
        if self._root is None:
            self._open()
        self._figure.clear()
        draw(self._figure.add_axes((0.0, 0.0, 1.0, 0.94)))
        self._canvas.draw()
        end = time.perf_counter() + pause
        while self._root is not None:
            self._root.update()
            if time.perf_counter() >= end:
                break
            time.sleep(0.02)

    def wait_closed(self) -> None:
        """Block until the user closes the window."""
        if self._root is not None:
            self._root.mainloop()

    @property
    def is_open(self) -> bool:
        return self._root is not None

    def close(self) -> None:
        if self._root is not None:
            self._root.destroy()
        self._root, self._figure, self._canvas, self._closed = None, None, None, True


def show_schematic(scene: Scene) -> None:
    """The labelled schematic of `scene`'s declared state in a window, until it is closed."""
    labels = LabelledSchematic(scene.object_names)
    labels.reset(scene)
    poses = np.array([[*scene.poses[n].position, *scene.poses[n].quat] for n in labels.names])
    window = SchematicWindow(f"utamp view {scene.name}")
    window.show(lambda ax: labels.draw(ax, poses, np.ones(len(poses)), None), 0.0)
    window.wait_closed()


class Rendering:
    """What ``render()`` returns and what the human windows show, for one env (module doc).

    `frame()` renders the current state; `draw(axes)` draws the labelled schematic (symbolic
    grounding); `backend` is the physics backend (None in symbolic grounding).
    """

    def __init__(
        self,
        mode: str | None,
        frame: Callable[[], np.ndarray],
        draw: Callable[[Any], None],
        backend: object | None,
        title: str = "utamp_gym",
    ) -> None:
        self.mode, self._frame, self._draw, self._backend = mode, frame, draw, backend
        self._title = title
        self._frames: list[np.ndarray] = []
        self._unwatch: Callable[[], None] | None = None
        self._window: MujocoWindow | SchematicWindow | None = None
        self._clock: tuple[float, float] | None = None  # (wall, simulated) time at sync
        if mode == "human" and backend is not None and not is_live(backend):
            raise ValueError(
                f"render_mode='human' in physics grounding needs a backend with a live "
                f"MuJoCo model (model, data, watch); {type(backend).__name__} has none"
            )
        self.attach()

    def attach(self) -> None:
        """Watch the backend while actions run (``rgb_array_list``, ``human``) and make the
        window; done when made, and again after unpickling (the env calls it)."""
        backend, live = self._backend, is_live(self._backend)
        if self.mode == "rgb_array_list" and live:
            self._unwatch = backend.watch(self._record, 1.0 / FRAME_RATE)  # type: ignore[union-attr]
        elif self.mode == "human":
            require_display("render_mode='human'", "render_mode='rgb_array'")
            if live:
                self._window = MujocoWindow()
                self._unwatch = backend.watch(self._sync, 1.0 / HUMAN_SYNC_HZ)  # type: ignore[union-attr]
            else:
                self._window = SchematicWindow(self._title)

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the window and the watch on the backend (`attach` makes them)."""
        return {**self.__dict__, "_unwatch": None, "_window": None, "_clock": None}

    @property
    def fps(self) -> int:
        """Frames per second of the frames `render()` gives (the env's ``render_fps``)."""
        live = is_live(self._backend)
        return FRAME_RATE if self.mode in ("rgb_array_list", "human") and live else STEP_RATE

    # ------------------------------------------------------------------ env hooks
    def reset(self) -> None:
        """After the env's reset: the first frame, or the window shows the new episode."""
        self._frames.clear()
        self._clock = None
        self._show()

    def step(self) -> None:
        """After every env step: the state after the action."""
        self._clock = None
        self._show()

    def render(self) -> np.ndarray | list[np.ndarray] | None:
        if self.mode == "rgb_array":
            return self._frame()
        if self.mode == "rgb_array_list":
            frames, self._frames = self._frames, []
            return frames
        return None  # "human" draws by itself (Gymnasium's convention)

    def close(self) -> None:
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None
        if self._window is not None:
            self._window.close()

    # ------------------------------------------------------------------ internals
    def _show(self) -> None:
        if self.mode == "rgb_array_list":
            self._frames.append(self._frame())
        elif isinstance(self._window, MujocoWindow):
            backend: Any = self._backend
            self._window.show(backend.model, backend.data)
        elif isinstance(self._window, SchematicWindow):
            self._window.show(self._draw, 1.0 / SYMBOLIC_HUMAN_FPS)

    def _record(self) -> None:
        self._frames.append(self._frame())

    def _sync(self) -> None:
        """While an action runs: sync the viewer and keep simulated time at real time."""
        window = self._window
        if not isinstance(window, MujocoWindow) or not window.is_open:
            return
        window.sync()
        now, sim = time.perf_counter(), float(self._backend.data.time)  # type: ignore[union-attr]
        if self._clock is None:
            self._clock = (now, sim)
            return
        ahead = (sim - self._clock[1]) - (now - self._clock[0])
        if ahead > 0:
            time.sleep(ahead)
