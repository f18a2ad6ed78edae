"""The one place that resolves packaged data: `assets/` and `envs/`.

In a source checkout (or an editable install) they are the top-level folders of
the repository; in a wheel they are shipped as ``utamp_gym/_data/{assets,envs}``.
"""

from __future__ import annotations

from pathlib import Path

from utamp_gym.errors import AssetError

_PKG = Path(__file__).resolve().parent


def _root(name: str) -> Path:
    for candidate in (_PKG / "_data" / name, _PKG.parent / name):
        if candidate.is_dir():
            return candidate
    raise AssetError(
        f"utamp_gym data folder '{name}' not found (looked in {_PKG / '_data' / name} "
        f"and {_PKG.parent / name}); reinstall the package"
    )


def assets_dir() -> Path:
    """Folder holding PDDL domains, the object catalogue, scene files and MuJoCo parts."""
    return _root("assets")


def envs_dir() -> Path:
    """Folder holding one env definition file per registered env id."""
    return _root("envs")


def asset_path(*parts: str) -> Path:
    """Path of a file under `assets/`; raises `AssetError` (an OSError) if it does not exist."""
    path = assets_dir().joinpath(*parts)
    if not path.exists():
        raise AssetError(f"asset not found: {path}")
    return path
