"""The optional extras (``pip install 'utamp-gym[EXTRA]'``): the modules each one provides, and
the one error that names a missing extra.

A command that needs an extra calls `require` before it does any work, so a missing extra
ends it at once with one line (the CLI exits 2) instead of a traceback after the work;
modules that import an extra when they load raise the same `MissingExtraError`.
"""

from __future__ import annotations

import importlib.util

from utamp_gym.errors import UtampError

EXTRAS: dict[str, tuple[str, ...]] = {
    "rl": ("torch", "stable_baselines3", "sb3_contrib"),
    "dm": ("dm_control", "dm_env"),
    "video": ("moviepy",),
    "dev": ("pytest", "ruff", "hypothesis"),
    "ray": ("ray",),
    # minari[hdf5]: the dataset and its HDF5 storage (the `create` extra's jax is not
    # imported by `utamp demos`)
    "data": ("minari", "h5py"),
    "zoo": ("rl_zoo3",),
    "docs": ("sphinx", "furo", "myst_parser"),
}
"""extra (as in pyproject.toml) -> the top-level modules a command needs from it."""


def install_command(extra: str) -> str:
    """The command that installs `extra`."""
    return f"pip install 'utamp-gym[{extra}]'"


class MissingExtraError(UtampError, ModuleNotFoundError):
    """A command or module needs an optional extra that is not installed (``name`` is the
    missing module); the message names the extra and how to install it, on one line."""

    def __init__(self, needed_by: str, extra: str, module: str, reason: str = "") -> None:
        reason = reason or f"no module named '{module}'"
        super().__init__(
            f"{needed_by} needs the '{extra}' extra ({reason}); install it: "
            f"{install_command(extra)}",
            name=module,
        )
        self.extra = extra


def missing_module(extra: str) -> str | None:
    """The first of `extra`'s modules that cannot be imported (found without importing it),
    or None when all are there."""
    for module in EXTRAS[extra]:
        try:
            found = importlib.util.find_spec(module) is not None
        except ValueError:  # imported already, without a spec
            found = True
        if not found:
            return module
    return None


def require(needed_by: str, *extras: str) -> None:
    """Raise `MissingExtraError` naming the first of `extras` that is not installed;
    `needed_by` is what needs it (``"utamp train"``, ``"utamp eval --executor ray"``)."""
    for extra in extras:
        module = missing_module(extra)
        if module is not None:
            raise MissingExtraError(needed_by, extra, module)
