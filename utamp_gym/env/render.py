"""Top-down schematic images of the table for symbolic grounding (no simulator needed).

Why: rendering and the ``image`` observation should work in the fast symbolic mode too. The
picture is a plan view: +x (away from the robot) points up, +y left; the robot base is the
dark square at the bottom. The workspace is outlined in dark grey, the slots in light grey,
free spaces in blue. Each object is its footprint in a fixed colour per observation row,
brighter the higher it stands, drawn bottom-up. It is a schematic, not a camera image:
physics grounding renders the simulator instead.

* `SchematicRenderer` (numpy, < 1 ms): axis-aligned footprints, a held object outlined in
  white; for the ``image`` observation.
* `LabelledSchematic` (matplotlib): what ``render()`` shows: oriented footprints labelled
  by name (a tower's labels listed top to bottom), slots, spaces and the workspace named,
  the held object outlined in red and marked "(held)", the hand's state in the title. It
  draws into an RGB array (Agg, no display) or into a window's axes (`draw`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from utamp_gym.perception.abstraction import quat_matrix
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
        if self._scene is None or self._scene.key != scene.key:
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


LABEL_STEP = 0.035  # m between the labels of objects stacked at one place
SAME_PLACE = 0.05  # m: footprint centres this close share a label column


def footprint(scene: Scene, name: str, pose: Sequence[float]) -> np.ndarray:
    """(4, 2) world xy corners of an upright or inverted object's bounding-box footprint."""
    box = scene.type_of(name).bbox
    rot, pos = quat_matrix(pose[3:7]), np.asarray(pose[:3], dtype=float)
    corners = [
        (box.min[0], box.min[1]),
        (box.max[0], box.min[1]),
        (box.max[0], box.max[1]),
        (box.min[0], box.max[1]),
    ]
    return np.array([(rot @ np.array([x, y, box.max[2]]) + pos)[:2] for x, y in corners])


class LabelledSchematic:
    """The labelled plan view of one scene (module docstring), drawn with matplotlib."""

    def __init__(self, names: Sequence[str]) -> None:
        self.names = tuple(names)
        self._scene: Scene | None = None
        self._figures: dict[tuple[int, int], Any] = {}  # (h, w) -> (Figure, canvas)

    def reset(self, scene: Scene) -> None:
        self._scene = scene

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without its figures (they are caches)."""
        return {**self.__dict__, "_figures": {}}

    def render(
        self, poses: np.ndarray, present: np.ndarray, held: str | None, size: tuple[int, int]
    ) -> np.ndarray:
        """A fresh uint8 (height, width, 3) image (Agg canvas, no display needed)."""
        if size not in self._figures:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            dpi = 100
            fig = Figure(figsize=(size[1] / dpi, size[0] / dpi), dpi=dpi)
            self._figures[size] = (fig, FigureCanvasAgg(fig))
        fig, canvas = self._figures[size]
        fig.clear()
        self.draw(fig.add_axes((0.0, 0.0, 1.0, 0.94)), poses, present, held)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()

    def draw(self, ax: Any, poses: np.ndarray, present: np.ndarray, held: str | None) -> None:
        """Draw the plan view into matplotlib axes `ax` (rows of `poses` follow `names`)."""
        from matplotlib.patches import Polygon, Rectangle

        scene = self._scene
        assert scene is not None, "reset(scene) first"

        def uv(x: float, y: float) -> tuple[float, float]:
            return -y, x  # plan view: +x up, +y left

        def rect(box: Any, **style: Any) -> None:
            (u0, v0), (u1, v1) = uv(box.max[0], box.max[1]), uv(box.min[0], box.min[1])
            ax.add_patch(Rectangle((u0, v1), u1 - u0, v0 - v1, fill=False, **style))

        ax.set_facecolor(np.array(TABLE) / 255)
        rect(scene.workspace, edgecolor=(0.35, 0.31, 0.27), linewidth=1.5)
        ws = scene.workspace
        ax.text(
            *uv(ws.min[0], ws.min[1]),
            "workspace ",
            va="bottom",
            ha="right",
            fontsize=7,
            color=(0.35, 0.31, 0.27),
        )
        for slot in scene.slots:
            rect(slot.region, edgecolor=(0.97, 0.95, 0.9), linewidth=1.2)
            ax.text(
                *uv(slot.region.max[0], slot.region.max[1]),
                f" {slot.name}",
                va="top",
                ha="left",
                fontsize=8,
                color=(0.45, 0.4, 0.33),
            )
        for space in scene.spaces:
            rect(space.box, edgecolor=(0.27, 0.47, 0.86), linewidth=1.0, linestyle="--")
            ax.text(
                *uv(space.box.min[0], space.box.max[1]),
                f" {space.name}",
                va="bottom",
                ha="left",
                fontsize=7,
                color=(0.27, 0.47, 0.86),
            )
        ax.add_patch(Rectangle(uv(-0.06, 0.06), 0.12, 0.12, color=(0.2, 0.2, 0.2)))
        ax.text(*uv(0.02, 0.0), "robot", ha="center", va="center", fontsize=7, color="white")
        rows = {n: i for i, n in enumerate(self.names)}
        objects = [o.name for o in scene.objects if present[rows[o.name]]]
        tops = {n: float(poses[rows[n], 2]) + scene.type_of(n).bbox.max[2] for n in objects}
        labelled: list[np.ndarray] = []
        for name in sorted(objects, key=lambda n: -tops[n]):  # labels: top of a stack first
            pose = poses[rows[name]]
            corners = footprint(scene, name, pose)
            centre = corners.mean(axis=0)
            shade = 0.55 + 0.45 * min(1.0, max(0.0, tops[name] / 0.4))
            colour = np.clip(PALETTE[rows[name] % len(PALETTE)] * shade / 255, 0, 1)
            is_held = name == held
            ax.add_patch(
                Polygon(
                    [uv(x, y) for x, y in corners],
                    facecolor=colour,
                    edgecolor=(0.85, 0.1, 0.1) if is_held else (0.16, 0.16, 0.16),
                    linewidth=2.5 if is_held else 0.8,
                    zorder=2 + tops[name],
                )
            )
            k = sum(np.linalg.norm(c - centre) < SAME_PLACE for c in labelled)
            labelled.append(centre)
            u, v = uv(*centre)
            ax.text(
                u,
                v - k * LABEL_STEP,
                name + (" (held)" if is_held else ""),
                ha="center",
                va="center",
                fontsize=9,
                fontweight="bold",
                zorder=10,
                color=(0.85, 0.1, 0.1) if is_held else "black",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "alpha": 0.7, "lw": 0},
            )
        boxes = [scene.workspace] + [s.region for s in scene.slots]
        x0 = min(0.0, *(b.min[0] for b in boxes)) - MARGIN
        x1 = max(b.max[0] for b in boxes) + MARGIN
        y0 = min(b.min[1] for b in boxes) - MARGIN
        y1 = max(b.max[1] for b in boxes) + MARGIN
        ax.set_xlim(-y1, -y0)
        ax.set_ylim(x0, x1)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xticks([])
        ax.set_yticks([])
        hand = f"hand holds {held}" if held else "hand empty"
        ax.figure.suptitle(f"{scene.name}: {hand}", fontsize=10, y=0.995, va="top")
