"""Old import paths kept for one release after a module moved to another sub-package.

A moved module leaves a shim at its old path that forwards every public name to the new
module and warns (`DeprecationWarning`) on each use, naming the new path::

    import utamp_gym.contract.views as _new
    from utamp_gym.moved import forward

    __getattr__, __dir__ = forward(__name__, _new)

A module whose names moved *up* (to a layer above it: `env.planner_policy` -> `agents`) must
not import its new home when loaded: `moved` resolves each name on first use instead.
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable, Iterable
from types import ModuleType
from typing import Any


def forward(old: str, new: ModuleType) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A shim module's ``__getattr__`` and ``__dir__``: `new`'s public names, with a warning."""

    def __getattr__(name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        try:
            value = getattr(new, name)
        except AttributeError:
            raise AttributeError(f"module {old!r} has no attribute {name!r}") from None
        warnings.warn(
            f"{old}.{name} moved to {new.__name__}.{name}: import it from there "
            "(the old path goes in the next release)",
            DeprecationWarning,
            stacklevel=2,
        )
        return value

    def __dir__() -> list[str]:
        return sorted(n for n in getattr(new, "__all__", dir(new)) if not n.startswith("_"))

    return __getattr__, __dir__


def moved(old: str, new: str, names: Iterable[str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for module `old`, whose `names` now live in module `new`."""
    known = frozenset(names)

    def __getattr__(name: str) -> Any:
        if name not in known:
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        warnings.warn(
            f"{old}.{name} moved to {new}.{name}; the old path goes away in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(importlib.import_module(new), name)

    return __getattr__


__all__ = ["forward", "moved"]
