"""The scene image shown to a VLM: the physics world rendered headless from the overview camera."""

from __future__ import annotations

import numpy as np

from utamp_gym.errors import SimulationError
from utamp_gym.scene.model import Scene
from utamp_gym.sim.gl import new_renderer

IMAGE_SIZE = (640, 480)  # width, height
CAMERA = "overview"


def render_scene_png(scene: Scene, seed: int = 0, size: tuple[int, int] = IMAGE_SIZE) -> bytes:
    """PNG bytes of `scene` in its initial configuration (no robot), seeded pose noise.

    Needs an offscreen GL context (`utamp_gym.sim.gl` picks one when ``MUJOCO_GL`` is unset);
    anything missing raises `SimulationError` naming what to install or set.
    """
    try:  # MuJoCo and GL load when an image is asked for, not on `utamp eval`'s start-up
        import imageio.v3 as iio
        import mujoco

        # lazy: utamp_gym.sim.world imports mujoco
        from utamp_gym.sim.world import build_world
    except ImportError as exc:  # pragma: no cover - the physics extras are dependencies
        raise SimulationError(f"cannot render the scene image: {exc}") from exc
    world = build_world(scene, rng=np.random.default_rng(seed))
    data = world.make_data()
    mujoco.mj_forward(world.model, data)
    width, height = size
    vis = world.model.vis.global_
    vis.offwidth, vis.offheight = max(vis.offwidth, width), max(vis.offheight, height)
    try:
        renderer = new_renderer(world.model, height, width)
    except Exception as exc:  # GL context errors come in several types
        raise SimulationError(f"cannot render the scene image: {exc}") from exc
    try:
        renderer.update_scene(data, camera=CAMERA)
        pixels = renderer.render()
    finally:
        renderer.close()
    return bytes(iio.imwrite("<bytes>", pixels, extension=".png"))
