"""How a handle member's box is realised: one reading shared by the simulator and the rules.

A handle beside the body (touching it along a horizontal axis) that leaves a finger-sized
opening is a loop of bars, gripped at its outer bar (`sim.bodies` builds it so, `sim.decode`
puts the fingers there and `affordances.hand` reasons about the same place); a handle apart
from the body is a bar on posts; anything else is solid.
"""

from __future__ import annotations

from utamp_gym.scene.catalogue import Member, ObjectType
from utamp_gym.scene.geometry import Box

BAR = 0.008  # m, bar thickness of a loop handle
LOOP_OPENING = (0.015, 0.03)  # m, smallest (outward, vertical) opening of a loop handle


def touch_axis(a: Box, b: Box, tol: float = 1e-6) -> tuple[int, int] | None:
    """(axis, sign) if box `a` lies beside `b` along one axis (touching or apart), else None."""
    for ax in range(3):
        others = [i for i in range(3) if i != ax]
        if not all(a.min[i] < b.max[i] and b.min[i] < a.max[i] for i in others):
            continue
        if a.min[ax] >= b.max[ax] - tol:
            return ax, 1
        if a.max[ax] <= b.min[ax] + tol:
            return ax, -1
    return None


def loop_axis(t: ObjectType, m: Member) -> tuple[int, int] | None:
    """(axis, sign) pointing out of the body if `m` is a loop handle, else None."""
    if m.kind != "handle" or m.geom != "box":
        return None
    side = touch_axis(m.box, t.body.box)
    if side is None or side[0] == 2:
        return None
    ax, sign = side
    gap = (m.box.min[ax] - t.body.box.max[ax]) if sign > 0 else (t.body.box.min[ax] - m.box.max[ax])
    if gap > 1e-6:
        return None
    out_len = m.box.max[ax] - m.box.min[ax]
    height = m.box.max[2] - m.box.min[2]
    if out_len - BAR >= LOOP_OPENING[0] and height - 2 * BAR >= LOOP_OPENING[1]:
        return side
    return None


__all__ = ["BAR", "LOOP_OPENING", "loop_axis", "touch_axis"]
