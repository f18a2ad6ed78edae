"""`surface_points`: points on an object's simulated surfaces, the robot's model of it.

Handed to a pose tracker (`utamp_gym.contract.tracking.PoseTracking`) at every reset: the
points about `spacing` apart on the surfaces of the collision primitives a catalogue type
is simulated with (`bodies.object_prims`), and their outward normals, in the object frame.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.sim.bodies import object_prims


def surface_points(t: ObjectType, spacing: float = 0.005) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, 3) about `spacing` apart on the surfaces of the type's collision
    primitives (`bodies.object_prims`) and their outward normals, in the object frame: the
    robot's model of it."""
    pts, nrm = [], []
    for p in object_prims(t):
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, np.asarray(p.quat, dtype=float))
        r = rot.reshape(3, 3)
        local, normal = _primitive_surface(p.shape, np.asarray(p.size, dtype=float), spacing)
        pts.append(local @ r.T + np.asarray(p.pos))
        nrm.append(normal @ r.T)
    return np.concatenate(pts), np.concatenate(nrm)


def _grid(a: float, b: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    u = np.linspace(-a, a, max(2, round(2 * a / spacing) + 1))
    v = np.linspace(-b, b, max(2, round(2 * b / spacing) + 1))
    uu, vv = np.meshgrid(u, v, indexing="ij")
    return uu.ravel(), vv.ravel()


def _primitive_surface(
    shape: str, size: np.ndarray, spacing: float
) -> tuple[np.ndarray, np.ndarray]:
    """Surface points of a primitive centred at the origin, and their unit normals."""
    if shape == "box":
        faces, normals = [], []
        for ax, (a, b) in enumerate(((size[1], size[2]), (size[0], size[2]), (size[0], size[1]))):
            u, v = _grid(a, b, spacing)
            for sign in (-1.0, 1.0):
                f = np.zeros((len(u), 3))
                f[:, ax] = sign * size[ax]
                others = [i for i in range(3) if i != ax]
                f[:, others[0]], f[:, others[1]] = u, v
                n = np.zeros_like(f)
                n[:, ax] = sign
                faces.append(f)
                normals.append(n)
        return np.concatenate(faces), np.concatenate(normals)
    if shape == "cylinder":
        r, h = float(size[0]), float(size[1])
        n = max(8, round(2 * math.pi * r / spacing))
        ang = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
        zs = np.linspace(-h, h, max(2, round(2 * h / spacing) + 1))
        aa, zz = np.meshgrid(ang, zs, indexing="ij")
        radial = np.column_stack([np.cos(aa.ravel()), np.sin(aa.ravel()), np.zeros(aa.size)])
        side = radial * r
        side[:, 2] = zz.ravel()
        u, v = _grid(r, r, spacing)
        disc = (u**2 + v**2) <= r * r
        caps, cap_n = [], []
        for z in (-h, h):
            caps.append(np.column_stack([u[disc], v[disc], np.full(disc.sum(), z)]))
            cap_n.append(np.tile([0.0, 0.0, math.copysign(1.0, z)], (int(disc.sum()), 1)))
        return np.concatenate([side, *caps]), np.concatenate([radial, *cap_n])
    a, b, c = size  # ellipsoid
    n = max(8, round(2 * math.pi * max(a, b) / spacing))
    th = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    ph = np.linspace(-math.pi / 2, math.pi / 2, max(4, n // 2))
    tt, pp = np.meshgrid(th, ph, indexing="ij")
    cp, sp, ct, st = np.cos(pp.ravel()), np.sin(pp.ravel()), np.cos(tt.ravel()), np.sin(tt.ravel())
    pts = np.column_stack([a * cp * ct, b * cp * st, c * sp])
    grad = np.column_stack([pts[:, 0] / a**2, pts[:, 1] / b**2, pts[:, 2] / c**2])
    grad /= np.maximum(np.linalg.norm(grad, axis=1, keepdims=True), 1e-12)
    return pts, grad


__all__ = ["surface_points"]
