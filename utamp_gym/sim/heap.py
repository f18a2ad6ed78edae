"""Give freed heap memory back to the operating system between episodes (glibc's malloc_trim).

Why: every `MujocoBackend.reset` compiles a new world (the Panda's meshes, collision models,
MuJoCo model and data: tens of MB of C allocations) and frees the previous one. glibc keeps the
freed blocks in its heap, where the next episode's differently sized blocks fragment them, so a
long run's resident size crept up by tens of MB over a few hundred resets although nothing
leaked. ``malloc_trim(0)`` returns the free pages (`benchmarks/memory.py` measures long runs).
A no-op where the C library has no ``malloc_trim`` (macOS, musl).
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable


@functools.cache
def _malloc_trim() -> Callable[[int], int] | None:
    try:  # the C library is loaded into every CPython process: look the symbol up there
        return ctypes.CDLL(None).malloc_trim  # type: ignore[no-any-return]
    except (OSError, AttributeError, TypeError):
        return None


def release_free_memory() -> bool:
    """Return the C heap's free pages to the OS; False if this C library cannot."""
    trim = _malloc_trim()
    if trim is None:
        return False
    trim(0)
    return True
