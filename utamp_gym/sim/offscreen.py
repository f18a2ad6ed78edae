"""`Offscreen`: MuJoCo's low-level offscreen renderer, depth and segment ids in one pass.

Why not `mujoco.Renderer`: it renders once per kind of image, so depth and segmentation cost
two passes of the same scene (both with the segmentation colours: MuJoCo draws depth that
way for its precision), and on a CPU rasteriser (EGL or OSMesa over llvmpipe) the pass and
its read-back are most of a camera look's time. One pass here fills the colour buffer with
segment colours and the depth buffer at once; one `mjr_readPixels` reads both. The depth is
converted to metres exactly as `mujoco.Renderer` converts it (reversed Z, float32 result), and
the images equal that renderer's, pixel for pixel (tests/test_rgbd_perception.py compares them under
mujoco 3 and 4). Only the public low-level API is used: a GL context of the backend
`utamp_gym.sim.gl.ensure_gl` chose, `MjrContext`, `mjv_updateScene`, `mjr_render`,
`mjr_readPixels`.

Shadows, reflections and the skybox are off in every pass (cameras of a perceiver, not a
film): the colour pass is plain lit colour.
"""

from __future__ import annotations

import contextlib

import mujoco
import numpy as np

from utamp_gym.sim.gl import ensure_gl

_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)
_OFF = (
    mujoco.mjtRndFlag.mjRND_SHADOW,
    mujoco.mjtRndFlag.mjRND_REFLECTION,
    mujoco.mjtRndFlag.mjRND_SKYBOX,
)
_SEGMENT = (mujoco.mjtRndFlag.mjRND_SEGMENT, mujoco.mjtRndFlag.mjRND_IDCOLOR)


class Offscreen:
    """An offscreen framebuffer of `width` x `height` for `model`'s fixed cameras."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        ensure_gl()
        vis = model.vis.global_
        vis.offwidth, vis.offheight = max(vis.offwidth, width), max(vis.offheight, height)
        self.model, self.width, self.height = model, width, height
        self._scene = mujoco.MjvScene(model, maxgeom=10000)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._gl = mujoco.GLContext(width, height)
        self._gl.make_current()
        self._context: mujoco.MjrContext | None = mujoco.MjrContext(
            model, mujoco.mjtFontScale.mjFONTSCALE_150.value
        )
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._context)
        self._context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        extent = model.stat.extent
        far = np.float32(model.vis.map.zfar * extent)
        near = np.float32(model.vis.map.znear * extent)
        # glFrustum's coefficients in float32, as MuJoCo's renderer, then reversed Z
        c = -(far + near) / (far - near)
        d = -(np.float32(2) * far * near) / (far - near)
        self._c = float(np.float32(-0.5) * c - np.float32(0.5))
        self._d = float(np.float32(-0.5) * d)
        for flag in _OFF:
            self._scene.flags[flag] = 0

    def update(self, data: mujoco.MjData, camera: int) -> None:
        """Build the scene of `data` as fixed camera `camera` (an id) sees it."""
        self._camera.fixedcamid = camera
        mujoco.mjv_updateScene(
            self.model,
            data,
            self._option,
            None,
            self._camera,
            mujoco.mjtCatBit.mjCAT_ALL.value,
            self._scene,
        )
        for flag in _OFF:
            self._scene.flags[flag] = 0

    def colour(self) -> np.ndarray:
        """The lit colour image (height, width, 3) of the last `update`."""
        for flag in _SEGMENT:
            self._scene.flags[flag] = 0
        rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        self._render(rgb, None)
        return np.flipud(rgb)

    def depth_and_geoms(self) -> tuple[np.ndarray, np.ndarray]:
        """Depth in metres (height, width; float32) and each pixel's geom id (-1: no geom)
        of the last `update`, from one segmentation pass."""
        for flag in _SEGMENT:
            self._scene.flags[flag] = 1
        rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        raw = np.empty((self.height, self.width), dtype=np.float32)
        try:
            self._render(rgb, raw)
        finally:
            for flag in _SEGMENT:
                self._scene.flags[flag] = 0
        depth = (self._d / (raw.astype(np.float64) + self._c)).astype(np.float32)
        seg = rgb.astype(np.int32)
        segid = seg[..., 0] | (seg[..., 1] << 8) | (seg[..., 2] << 16)
        # segment id + 1 per pixel (0: nothing drawn) -> the geom it shows
        n = self._scene.ngeom
        lut = np.full(n + 1, -1, dtype=np.int32)
        for g in self._scene.geoms[:n]:
            if g.segid != -1 and g.objtype == _GEOM:
                lut[g.segid + 1] = g.objid
        return np.flipud(depth), np.flipud(lut[segid])

    def _render(self, rgb: np.ndarray | None, depth: np.ndarray | None) -> None:
        if self._context is None:
            raise RuntimeError("render after close")
        self._gl.make_current()
        mujoco.mjr_render(self._rect, self._scene, self._context)
        mujoco.mjr_readPixels(rgb, depth, self._rect, self._context)

    def close(self) -> None:
        """Free the GL resources (idempotent)."""
        if self._context is not None:
            self._gl.make_current()
            self._context.free()
            self._context = None
            self._gl.free()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # at interpreter exit GL may be gone already
            self.close()


__all__ = ["Offscreen"]
