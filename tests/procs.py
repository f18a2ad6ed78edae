"""Process helpers for tests that check no planner process is left behind (Linux /proc)."""

from __future__ import annotations

import os
from pathlib import Path


def downward_children(pid: int | None = None) -> list[int]:
    """Pids of live (non-zombie) ``downward`` processes whose parent is `pid` (default: this
    process)."""
    parent = os.getpid() if pid is None else pid
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        comm = stat[stat.index("(") + 1 : stat.rindex(")")]
        state, ppid = stat[stat.rindex(")") + 2 :].split()[:2]
        if comm == "downward" and int(ppid) == parent and state != "Z":
            found.append(int(entry.name))
    return found


def process_alive(pid: int) -> bool:
    """Whether `pid` exists and is not a zombie."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"


#: variables a test's own process may have set or inherited that a user's shell has not:
#: the GL choice (`utamp_gym.sim.gl` writes MUJOCO_GL once it has probed; MuJoCo's EGL
#: module sets PYOPENGL_PLATFORM) and the display
NOT_A_USERS = ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY")


def user_env(**extra: str) -> dict[str, str]:
    """The environment of a headless user's shell for a child process: this one's without
    `NOT_A_USERS`, plus `extra`. Every test subprocess uses it, so tests see what users see."""
    env = {k: v for k, v in os.environ.items() if k not in NOT_A_USERS}
    return {**env, **extra}
