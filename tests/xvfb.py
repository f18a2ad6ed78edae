"""A private X display for GUI tests (Debian's Xvfb) and screenshots of it.

`virtual_display()` starts ``Xvfb`` on a free display number (``-displayfd``) with its screen
mirrored to an XWD file (``-fbdir``), yields a `Display`, and stops the server. Tests skip
with a reason when Xvfb is not installed (``apt-get install -y xvfb``).
"""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from procs import user_env

SCREEN = (1024, 768)


@dataclass(frozen=True)
class Display:
    """A running Xvfb server: its ``DISPLAY`` value and its mirrored framebuffer file."""

    name: str
    framebuffer: Path

    def env(self, **extra: str) -> dict[str, str]:
        """A desktop user's environment (`procs.user_env`: no ``MUJOCO_GL``, no
        ``PYOPENGL_PLATFORM``, which MuJoCo's EGL module sets in this process and which a
        window's GLX context must not have) with ``DISPLAY`` pointing here and `extra` set."""
        return user_env(DISPLAY=self.name, **extra)

    def screenshot(self) -> np.ndarray:
        """The screen as an RGB array (height, width, 3), read from the XWD framebuffer."""
        raw = self.framebuffer.read_bytes()
        header = struct.unpack(">25I", raw[:100])
        size, width, height, bpl, ncolors = header[0], header[4], header[5], header[12], header[19]
        offset = size + 12 * ncolors
        pixels = np.frombuffer(raw, np.uint8, count=bpl * height, offset=offset)
        return pixels.reshape(height, bpl // 4, 4)[:, :width, 2::-1].copy()  # BGRX -> RGB


def wait_until(predicate: object, timeout: float, what: str) -> None:
    """Poll `predicate()` every 0.2 s; fail the test naming `what` after `timeout` s."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():  # type: ignore[operator]
            return
        time.sleep(0.2)
    pytest.fail(f"timed out after {timeout:.0f} s waiting for {what}")


def _start_xvfb(fbdir: str) -> tuple[subprocess.Popen[bytes], Display]:
    """Start Xvfb on a free display number, its screen mirrored into `fbdir`."""
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen(
        [
            "Xvfb", "-displayfd", str(write_fd), "-screen", "0",
            f"{SCREEN[0]}x{SCREEN[1]}x24", "-fbdir", fbdir, "-nolisten", "tcp",
        ],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    os.close(write_fd)
    with os.fdopen(read_fd) as pipe:
        number = pipe.readline().strip()
    if not number:
        proc.wait()
        pytest.skip(f"Xvfb did not start (exit code {proc.returncode})")
    return proc, Display(f":{number}", Path(fbdir) / "Xvfb_screen0")


@contextmanager
def virtual_display() -> Iterator[Display]:
    """A private Xvfb for windows of *child* processes; stopped when the block ends.

    (A process that opened a Tk window itself must keep its display until it exits: Tk
    never closes the connection, and a vanished server kills the process.)
    """
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (Debian: apt-get install -y xvfb)")
    with tempfile.TemporaryDirectory(prefix="utamp-xvfb-") as tmp:
        proc, display = _start_xvfb(tmp)
        try:
            yield display
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def process_display() -> Display | None:
    """An Xvfb that outlives this process's windows: a watchdog shell stops it (and removes
    its framebuffer directory) once this process has exited. None without Xvfb."""
    if shutil.which("Xvfb") is None:
        return None
    tmp = tempfile.mkdtemp(prefix="utamp-xvfb-")
    proc, display = _start_xvfb(tmp)
    watchdog = (
        f"while kill -0 {os.getpid()} 2>/dev/null; do sleep 1; done; kill {proc.pid}; rm -rf {tmp}"
    )
    subprocess.Popen(["sh", "-c", watchdog], start_new_session=True)
    return display
