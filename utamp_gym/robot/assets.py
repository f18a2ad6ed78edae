"""Locate the Franka Panda description shipped by the `example-robot-data` wheel.

The wheel (6.x) holds only files, no importable module, so the files are found
through the distribution's record. Nothing is downloaded.
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from utamp_gym.errors import AssetError

DISTRIBUTION = "example-robot-data"
_URDF_SUFFIX = "robots/panda_description/urdf/panda.urdf"


@dataclass(frozen=True)
class PandaAssets:
    """Absolute paths of the Panda description files (URDF, SRDF, collision meshes)."""

    root: Path  # .../robots/panda_description
    urdf: Path
    srdf: Path
    collision_mesh_dir: Path
    package_dir: Path  # folder that resolves `package://example-robot-data/...`

    def collision_mesh(self, name: str) -> Path:
        """Absolute path of a collision STL, e.g. ``collision_mesh("link3")``."""
        path = self.collision_mesh_dir / f"{name}.stl"
        if not path.is_file():
            raise AssetError(f"Panda collision mesh not found: {path}")
        return path

    def resolve_uri(self, uri: str) -> Path:
        """Turn a ``package://example-robot-data/...`` URI (or a plain path) into a file path."""
        prefix = "package://"
        if uri.startswith(prefix):
            return self.package_dir / uri[len(prefix) :]
        return Path(uri)


@functools.cache
def panda_assets() -> PandaAssets:
    """Find the Panda files; raises `AssetError` naming what is missing.

    The result is immutable and cached (scanning the wheel's record takes ~10 ms).
    """
    try:
        dist = metadata.distribution(DISTRIBUTION)
    except metadata.PackageNotFoundError as exc:
        raise AssetError(
            f"Python distribution '{DISTRIBUTION}' is not installed; it provides the Franka "
            f"Panda URDF/meshes (pip install 'example-robot-data>=5')"
        ) from exc
    hits = [f for f in (dist.files or []) if str(f).replace("\\", "/").endswith(_URDF_SUFFIX)]
    if not hits:
        raise AssetError(
            f"'{DISTRIBUTION}' {dist.version} is installed but its record lists no "
            f"'{_URDF_SUFFIX}'; reinstall it"
        )
    urdf = Path(str(dist.locate_file(hits[0]))).resolve()
    root = urdf.parent.parent
    assets = PandaAssets(
        root=root,
        urdf=urdf,
        srdf=root / "srdf" / "panda.srdf",
        collision_mesh_dir=root / "meshes" / "collision",
        package_dir=root.parent.parent.parent,  # <share>/example-robot-data/robots/...
    )
    for path in (assets.urdf, assets.srdf, assets.collision_mesh_dir):
        if not path.exists():
            raise AssetError(
                f"Panda asset missing: {path} (from '{DISTRIBUTION}' {dist.version}); reinstall it"
            )
    return assets


def srdf_disabled_collisions(assets: PandaAssets | None = None) -> tuple[tuple[str, str], ...]:
    """Link pairs the SRDF marks as never/adjacent/default-colliding (URDF link names)."""
    assets = assets or panda_assets()
    try:
        root = ET.parse(assets.srdf).getroot()
    except (OSError, ET.ParseError) as exc:
        raise AssetError(f"cannot read Panda SRDF {assets.srdf}: {exc}") from exc
    return tuple((el.attrib["link1"], el.attrib["link2"]) for el in root.iter("disable_collisions"))
