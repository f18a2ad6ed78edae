"""A top-down schematic image of the table for symbolic grounding (no simulator needed).

Why: ``render_mode="rgb_array"`` and the ``image`` observation should work in the fast
symbolic mode too. The picture is a plan view: +x (away from the robot) points up, +y left;
the robot base is the dark square at the bottom. The workspace is outlined in dark grey, the
slots in light grey, free spaces in blue. Each object is its footprint (oriented bounding
box) in a fixed colour per observation row, brighter the higher it stands, drawn bottom-up;
a held object gets a white outline. It is a schematic, not a camera image: physics
grounding renders the simulator instead.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from utamp_gym.scene.model import Scene

PALETTE = np.array(
    [[166, 118, 29], [200, 200, 210], [90, 170, 220], [222, 160, 90], [60, 60, 70],
     [120, 200, 120], [200, 90, 160], [240, 220, 90]],
    np.float32,
)  # fmt: skip
TABLE = (214, 196, 160)
MARGIN = 0.08  # m around the table features


class SchematicRenderer:
    """Draws one scene's objects from their poses; backgrounds are cached per image size."""

    def __init__(self, names: Sequence[str]) -> None:
        self.names = tuple(names)
        self._scene: Scene | None = None
        self._foot = np.zeros((len(self.names), 4))  # xmin, ymin, xmax, ymax (object frame)
        self._top = np.zeros(len(self.names))  # bbox top z (object frame)
        self._bounds = (0.0, 1.0, -0.5, 0.5)
        self._background: dict[tuple[int, int], np.ndarray] = {}
        self._ready = False

    def reset(self, scene: Scene) -> None:
        """Draw `scene` from now on (prepared lazily: most episodes are never rendered)."""
        if self._scene is None or self._scene.name != scene.name:
            self._scene, self._ready = scene, False

    def _prepare(self) -> None:
        scene = self._scene
        assert scene is not None, "reset(scene) first"
        self._ready, self._background = True, {}
        rows = {n: i for i, n in enumerate(self.names)}
        for o in scene.objects:
            box = scene.oriented_bbox(o.name)
            self._foot[rows[o.name]] = (box.min[0], box.min[1], box.max[0], box.max[1])
            self._top[rows[o.name]] = box.max[2]
        boxes = [scene.workspace] + [s.region for s in scene.slots]
        x0 = min(0.0, *(b.min[0] for b in boxes)) - MARGIN
        x1 = max(b.max[0] for b in boxes) + MARGIN
        y0 = min(b.min[1] for b in boxes) - MARGIN
        y1 = max(b.max[1] for b in boxes) + MARGIN
        self._bounds = (x0, x1, y0, y1)

    def _pixels(
        self, size: tuple[int, int], xmin: float, ymin: float, xmax: float, ymax: float
    ) -> tuple[int, int, int, int]:
        """(row0, row1, col0, col1) of a world rectangle; +x up, +y left."""
        x0, x1, y0, y1 = self._bounds
        h, w = size
        scale = max((x1 - x0) / h, (y1 - y0) / w)
        r0, r1 = int((x1 - xmax) / scale), int(np.ceil((x1 - xmin) / scale))
        c0, c1 = int((y1 - ymax) / scale), int(np.ceil((y1 - ymin) / scale))
        return max(r0, 0), min(r1, h), max(c0, 0), min(c1, w)

    def _outline(
        self, img: np.ndarray, rect: tuple[int, int, int, int], colour: Sequence[int]
    ) -> None:
        r0, r1, c0, c1 = rect
        if r1 <= r0 or c1 <= c0:
            return
        img[r0, c0:c1] = img[r1 - 1, c0:c1] = colour
        img[r0:r1, c0] = img[r0:r1, c1 - 1] = colour

    def _base(self, size: tuple[int, int]) -> np.ndarray:
        if size not in self._background:
            assert self._scene is not None, "reset(scene) first"
            img = np.empty((*size, 3), np.uint8)
            img[:] = TABLE
            for slot in self._scene.slots:
                b = slot.region
                self._outline(
                    img, self._pixels(size, b.min[0], b.min[1], b.max[0], b.max[1]), (235, 225, 200)
                )
            for space in self._scene.spaces:
                b = space.box
                self._outline(
                    img, self._pixels(size, b.min[0], b.min[1], b.max[0], b.max[1]), (70, 120, 220)
                )
            ws = self._scene.workspace
            self._outline(
                img, self._pixels(size, ws.min[0], ws.min[1], ws.max[0], ws.max[1]), (90, 80, 70)
            )
            r0, r1, c0, c1 = self._pixels(size, -0.06, -0.06, 0.06, 0.06)
            img[r0:r1, c0:c1] = (50, 50, 50)
            self._background[size] = img
        return self._background[size]

    def render(
        self, poses: np.ndarray, present: np.ndarray, held: str | None, size: tuple[int, int]
    ) -> np.ndarray:
        """A fresh uint8 (height, width, 3) image of objects at `poses` (rows of `names`)."""
        if not self._ready:
            self._prepare()
        img = self._base(size).copy()
        tops = poses[:, 2] + self._top
        for i in sorted(np.flatnonzero(present), key=lambda k: tops[k]):
            x, y = poses[i, 0], poses[i, 1]
            f = self._foot[i]
            rect = self._pixels(size, x + f[0], y + f[1], x + f[2], y + f[3])
            shade = 0.55 + 0.45 * min(1.0, max(0.0, float(tops[i]) / 0.4))
            r0, r1, c0, c1 = rect
            img[r0:r1, c0:c1] = np.clip(PALETTE[i % len(PALETTE)] * shade, 0, 255)
            self._outline(img, rect, (255, 255, 255) if self.names[i] == held else (40, 40, 40))
        return img
