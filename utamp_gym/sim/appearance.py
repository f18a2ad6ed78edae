"""How each object instance looks: a colour and a finish sampled from its material.

Why per instance: a camera-based perceiver must infer the material from appearance, and
real kitchenware of one material comes in many colours (white ceramic and white plastic,
brown wood and brown cardboard, grey steel and grey plastic). So every instance whose type
declares no ``rgba`` draws its colour from its material's palette
(`utamp_gym.scene.materials`) with a little per-channel variation, and its finish
(specular highlight, shininess, mirror reflectance) varies around the material's; colour
alone then does not decide the material. A type's own ``rgba`` is kept (its finish still
comes from the material). The draws come from a child of the world's generator
(`numpy.random.Generator.spawn`), so they do not shift the physics stream (initial pose
noise, pose estimates, IK restarts) that the same generator feeds afterwards; without a
generator every instance takes its palette's first colour and the nominal finish.

The appearance becomes one MuJoCo material per object (``obj/<name>/material``); geoms
drawn in the accent colour (a shaker's metal head) share one steel-like material.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from utamp_gym.scene.materials import Finish, hex_rgba, material
from utamp_gym.scene.model import Scene

COLOUR_JITTER = 0.04  # per-channel uniform variation of a palette colour
FINISH_JITTER = 0.2  # relative uniform variation of each finish attribute
ACCENT_MATERIAL = "obj/accent"
ACCENT_RGBA = hex_rgba("bfbfc7ff")
ACCENT_FINISH = Finish(0.8, 0.7, 0.2)


class Appearance(NamedTuple):
    """Colour (rgba in [0, 1]) and finish of one object instance."""

    rgba: tuple[float, float, float, float]
    finish: Finish


def _child(rng: np.random.Generator) -> np.random.Generator:
    """A generator derived from `rng` without drawing from it (falls back to one draw)."""
    try:
        return rng.spawn(1)[0]
    except (TypeError, ValueError, AttributeError):  # no seed sequence to spawn from
        return np.random.default_rng(int(rng.integers(2**63)))


def object_appearance(
    scene: Scene, rng: np.random.Generator | None = None
) -> dict[str, Appearance]:
    """Colour and finish of every object of `scene` (see the module docstring)."""
    draw = None if rng is None else _child(rng)
    out: dict[str, Appearance] = {}
    for o in scene.objects:
        t = scene.type_of(o.name)
        mat = material(t.material)
        own = t.extra.get("rgba")
        if own is not None:
            rgba = tuple(float(v) for v in own)
        elif draw is None:
            rgba = hex_rgba(mat.palette[0])
        else:
            base = np.asarray(hex_rgba(mat.palette[int(draw.integers(len(mat.palette)))]))
            shift = draw.uniform(-COLOUR_JITTER, COLOUR_JITTER, 3)
            rgba = (*np.clip(base[:3] + shift, 0.0, 1.0).tolist(), float(base[3]))
        finish = mat.finish
        if draw is not None:
            scale = draw.uniform(1 - FINISH_JITTER, 1 + FINISH_JITTER, 3)
            finish = Finish(*np.clip(np.asarray(finish) * scale, 0.0, 1.0).tolist())
        out[o.name] = Appearance(rgba, finish)  # type: ignore[arg-type]
    return out


def material_name(obj: str) -> str:
    """The MuJoCo material of object `obj`."""
    return f"obj/{obj}/material"


def add_materials(spec: mujoco.MjSpec, appearances: dict[str, Appearance]) -> None:
    """One MuJoCo material per object (and the shared accent material)."""
    for name, app in {ACCENT_MATERIAL: Appearance(ACCENT_RGBA, ACCENT_FINISH)}.items():
        _material(spec, name, app)
    for obj, app in appearances.items():
        _material(spec, material_name(obj), app)


def _material(spec: mujoco.MjSpec, name: str, app: Appearance) -> None:
    mat = spec.add_material()
    mat.name = name
    mat.rgba = list(app.rgba)
    mat.specular = app.finish.specular
    mat.shininess = app.finish.shininess
    mat.reflectance = app.finish.reflectance


__all__ = [
    "ACCENT_MATERIAL",
    "Appearance",
    "add_materials",
    "material_name",
    "object_appearance",
]
