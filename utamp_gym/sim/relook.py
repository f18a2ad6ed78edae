"""The wrist camera's looks while the hand is at the object: aim a grasp, check it, aim a place.

Why: the scene cameras see the table from a metre away; the wrist camera, 15-20 cm from an
object, sees it several times more precisely (`estimate.CLOSE_FRACTION` in the Gaussian
model; the rendered wrist view with ``perception="rgbd"``), and it sees what happened since
the last look — a light shaker pushed aside by a finger on the way down, which no other
sensor of the robot notices. Three steps, each a plain function the skills call:

* `aim_grasp` — at the pre-grasp pose, before descending: look closely at the object; if
  it is more than `AIM_SHIFT` (or `AIM_TURN_DEG`) from where the grasp was planned, plan the
  grasp again from the closer estimate and move to its pre-grasp;
* `check_grasp` — at the grasp pose, fingers open around the member, before closing them:
  look once more; if the member's middle is farther from the fingers' axis than the open
  fingers leave room for (its width and `CHECK_MARGIN` on each side), back the hand off and
  report a missed grasp (the pick then looks again and retries, `skills.pick`);
* `aim_place` — over the support, before lowering: look closely at the support; if it is
  more than `AIM_SHIFT` from where the placement was planned, plan it again.

The object in the hand is always looked at with the wrist camera (`in_hand`), and a
placement is planned with room for the estimates' error (`place_room`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numpy as np

from utamp_gym.sim.decode import GraspPose, GraspSymbols, grasp_point
from utamp_gym.sim.measure import SimState, obj_pose, pose_change

AIM_SHIFT = 0.002  # m: a closer estimate farther than this re-aims
#: a placement may penetrate its support in the robot's belief by this many standard
#: deviations of the pose estimates (the error of the support's and the held object's)
PLACE_ROOM_SIGMAS = 3.0
AIM_TURN_DEG = 1.5
#: m a finger must clear the member by on each side. The look is itself uncertain (at 2 mm
#: pose noise the wrist camera's is 0.5 mm a side): a 2 mm margin left a body 74 mm wide in
#: the 80 mm opening 1.1 mm, and grasps aimed true to 0.01 mm were refused on a 1.1 mm look
CHECK_MARGIN = 0.001
#: the aim keeps the member's middle within this share of the room the check allows: the
#: rest is for the error of the check's own look (a body 73 mm wide in an 80 mm opening has
#: 1.5 mm; aimed 1.3 mm off, the next look saw 1.6 mm and the grasp was refused)
AIM_ROOM_SHARE = 0.5
Plan = TypeVar("Plan")


def _close(st: SimState, name: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(estimate before, close estimate) of `name`, or None without an estimator."""
    if st.estimator is None:
        return None
    before = st.estimate(name)
    return before, st.estimator.close_look(name, obj_pose(st, name))


def aim_grasp(
    st: SimState, sym: GraspSymbols, g: GraspPose, plan: Plan, replan: Callable[[], Plan]
) -> Plan:
    """`plan` (for grasp `g`), or a new one (`replan`, which uses the closer estimate) if the
    object is not where it was planned for: moved by more than `AIM_SHIFT` or turned by more
    than `AIM_TURN_DEG`, or off by less but by more than `AIM_ROOM_SHARE` of the room the
    open fingers leave (a wide body: the check before closing would refuse the grasp)."""
    looked = _close(st, sym.obj)
    if looked is None:
        return plan
    shift, turn = pose_change(*looked)
    fits = _beyond_reach(st, sym, g, looked[1], AIM_ROOM_SHARE) is None
    if shift <= AIM_SHIFT and turn <= AIM_TURN_DEG and fits:
        return plan
    return replan()


def _beyond_reach(
    st: SimState, sym: GraspSymbols, g: GraspPose, pose: np.ndarray, share: float = 1.0
) -> float | None:
    """How far (m) the grasped member's middle, with the object at `pose`, lies off the
    fingers' closing line beyond `share` of the room the open fingers leave (each side of
    the member, less `CHECK_MARGIN`); None: within it."""
    t = st.world.scene.type_of(sym.obj)
    point = pose[:3, :3] @ grasp_point(t, sym.member, sym.palm, sym.finger1) + pose[:3, 3]
    offset = point - g.tcp[:3, 3]
    finger_axis = g.tcp[:3, 1]  # the fingers close along the TCP's y axis
    along = abs(float(offset @ finger_axis))
    room = ((g.opening - g.width) / 2 - CHECK_MARGIN) * share
    return along - room if along > room else None


def grasp_offset(st: SimState, sym: GraspSymbols, g: GraspPose) -> float | None:
    """How far (m) the grasped member's middle lies off the fingers' closing line, as the
    wrist camera sees it now, beyond what the open fingers leave room for; None: in reach."""
    looked = _close(st, sym.obj)
    if looked is None:
        return None
    return _beyond_reach(st, sym, g, looked[1])


def aim_place(st: SimState, support: str, plan: Plan, replan: Callable[[], Plan]) -> Plan:
    """`plan`, or a new one if the closer look puts the support elsewhere (module docstring)."""
    if support not in st.world.body_ids:
        return plan  # a table slot does not move
    looked = _close(st, support)
    if looked is None:
        return plan
    shift, turn = pose_change(*looked)
    if shift <= AIM_SHIFT and turn <= AIM_TURN_DEG:
        return plan
    return replan()


def in_hand(st: SimState, name: str) -> np.ndarray:
    """The wrist camera's estimate of `name` in (or at) the hand; its true pose without an
    estimator."""
    if st.estimator is None:
        return obj_pose(st, name)
    return st.estimator.close_look(name, obj_pose(st, name))


def place_room(st: SimState) -> float:
    """How far (m, as a negative contact distance) the held object may seem to penetrate
    the support while a placement is planned (`PLACE_ROOM_SIGMAS`)."""
    noise = 0.0 if st.estimator is None else st.estimator.noise
    return -PLACE_ROOM_SIGMAS * noise


def describe(offset: float) -> str:
    return f"{offset * 1000:.0f} mm beyond the open fingers' reach"


__all__ = [
    "AIM_ROOM_SHARE",
    "AIM_SHIFT",
    "AIM_TURN_DEG",
    "CHECK_MARGIN",
    "aim_grasp",
    "aim_place",
    "describe",
    "grasp_offset",
    "in_hand",
    "place_room",
]
