"""How the hand takes a member: the grasp pose, its opening and an arm configuration that
reaches it with a feasible approach and lift.

`plan_grasp` tries both finger-axis signs (`decode.grasp_candidates`), then the grasps from
above raised up to `GRASP_RAISES` higher (`_raised`), several IK solutions each and the
widest opening that fits; the pick skill (`skills.pick`) moves along what it returns.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from utamp_gym.affordances.solids import centre_of_mass
from utamp_gym.errors import GroundingError
from utamp_gym.robot.collision import CollisionChecker
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.sim.bodies import BODY_PREFIX
from utamp_gym.sim.control import ArmDriver, LinePath, allowing, ignoring
from utamp_gym.sim.decode import (
    FINGER_CLEARANCE,
    MAX_OPENING,
    TIP_BELOW_TCP,
    GraspPose,
    GraspSymbols,
    grasp_candidates,
    world_aabb,
)
from utamp_gym.sim.measure import SimState, SkillFailure

UNCERTAINTY_SIGMAS = 3.0  # the fingers open this many pose-noise deviations wider a side
#: m a grasp from above is raised by, in turn, when no arm configuration reaches it, while
#: the pads keep `PAD_HOLD` of the member between them (`_raised`): a plate in a larger
#: plate's well (procedural-v1/test-count/0063) is pinched 15 mm higher, 7 mm of its rim
GRASP_RAISES, PAD_HOLD = (0.005, 0.01, 0.015), 0.006


def plan_grasp(
    st: SimState, sym: GraspSymbols, lift: float
) -> tuple[GraspPose, LinePath, LinePath]:
    """(grasp, approach path pre-grasp -> grasp, lift path) or `GroundingError`.

    Tries both finger-axis signs and several IK solutions; a solution is kept only if
    the straight approach and the lift (`lift` m up, 0: none) are feasible from it.
    """
    arm, world = st.arm, st.world
    t = world.scene.type_of(sym.obj)
    member = _member_geoms(st, sym.obj, sym.member)
    rest = [g for g in world.geom_ids[sym.obj] if g not in member]
    fingers = set(arm.ids.finger_geom_ids.tolist()) | set(arm.ids.finger_pad_geom_ids.tolist())
    palm = [g for g in arm.ids.geom_ids.tolist() if g not in fingers]
    tried = []
    pose = st.estimate(sym.obj)
    candidates = grasp_candidates(t, sym, pose, prefer_x=arm.tcp()[:3, 0])
    candidates += _raised(t, sym, pose, candidates)
    noise = 0.0 if st.estimator is None else st.estimator.noise
    if candidates[0].width > MAX_OPENING:
        raise SkillFailure(
            f"cannot grasp {sym.obj} by its {sym.member}: it is {candidates[0].width * 100:.0f} cm"
            f" between the fingers, the hand opens {MAX_OPENING * 100:.0f} cm"
        )
    for g in candidates:
        near = arm.sync(arm.near, gap=g.opening)
        # the fingers may touch the member only; the palm may rest against the rest of the
        # object (an upside-down pot's floor above its lug), as it would in the real hand
        with ignoring(near, member), allowing(near, palm, rest):
            for q in arm.ik_solutions(g.tcp, near.is_valid):
                # the widest opening that fits: room for the error of the pose estimate
                for opening in _openings(g, noise):
                    wide = replace(g, opening=opening)
                    arm.sync(near, gap=opening)
                    try:
                        if not near.is_valid(q):
                            continue
                        back, up = _approach_and_lift(arm, wide, q, lift, sym.obj, near)
                    except GroundingError as exc:
                        tried.append(str(exc))
                        continue
                    finally:
                        arm.sync(near, gap=g.opening)  # the IK search goes on at the narrowest
                    return wide, back.reversed(), up
        tried.append("no collision-free IK solution")
    raise GroundingError(
        f"IK infeasible: cannot grasp {sym.obj} by its {sym.member} with the palm on "
        f"'{sym.palm}' ({'; '.join(dict.fromkeys(tried))})"
    )


def _raised(
    t: ObjectType, sym: GraspSymbols, pose: np.ndarray, grasps: list[GraspPose]
) -> list[GraspPose]:
    """The grasps from above again, `GRASP_RAISES` higher, while the pads still hold
    `PAD_HOLD` of the member: a plate's rim in a larger plate's well, whose rim rises
    where the outer finger goes down, is pinched higher up."""
    top = float(world_aabb(t.members[sym.member].box, pose)[1][2])
    out = []
    for rise in GRASP_RAISES:
        for g in grasps:
            tip = float(g.tcp[2, 3]) + rise - TIP_BELOW_TCP
            if g.tcp[2, 2] > -0.5 or top - tip < PAD_HOLD:
                continue  # not from above, or too little of the member between the pads
            up = np.array([0.0, 0.0, rise])
            tcp, pre = g.tcp.copy(), g.pregrasp.copy()
            tcp[:3, 3] += up
            pre[:3, 3] += up
            out.append(replace(g, tcp=tcp, pregrasp=pre))
    return out


def _member_geoms(st: SimState, obj: str, member: str) -> list[int]:
    """The geoms realising `member` of `obj` (the fingers may touch them, not the rest of the
    object: a finger must not land on a tray's rim next to its handle); all of the object's
    geoms if the member has none of its own (an edge realised by the body's wall)."""
    prefix = f"{BODY_PREFIX}{obj}/{member}"
    names = st.world.info.geom_names[obj]
    own = [
        g
        for g, name in zip(st.world.geom_ids[obj], names, strict=True)
        if name == prefix or name.startswith(prefix + "/")
    ]
    return own or list(st.world.geom_ids[obj])


def _openings(g: GraspPose, noise: float) -> tuple[float, ...]:
    """Pre-grasp finger openings to try, widest first: room for 3 standard deviations of the
    pose estimate's error on each side (within the hand's opening), then the member's width
    plus `FINGER_CLEARANCE` a side (`GraspPose.opening`)."""
    wide = min(MAX_OPENING, g.width + 2 * (FINGER_CLEARANCE + UNCERTAINTY_SIGMAS * noise))
    return (wide, g.opening) if wide > g.opening + 1e-9 else (g.opening,)


def _approach_and_lift(
    arm: ArmDriver, g: GraspPose, q: np.ndarray, lift: float, obj: str, near: CollisionChecker
) -> tuple[LinePath, LinePath]:
    """(path grasp -> pre-grasp, lift path) from grasp configuration `q`, or GroundingError."""
    back = arm.line(q, g.tcp, g.pregrasp[:3, 3] - g.tcp[:3, 3], near.is_valid, what="the approach")
    up = arm.line(q, g.tcp, np.array([0.0, 0.0, lift]), near.is_valid, what=f"lifting {obj}")
    return back, up


__all__ = ["GRASP_RAISES", "PAD_HOLD", "UNCERTAINTY_SIGMAS", "plan_grasp"]


def weight_moment(t: ObjectType, obj_world: np.ndarray, tcp_world: np.ndarray) -> float:
    """N m: the moment of `t`'s catalogue weight about the grasp point (`tcp_world`), its
    centre of mass where `obj_world` puts it (what the robot expects to hold; it sets the
    pinch force, `ArmDriver.expect_width`)."""
    cx, cy = centre_of_mass(t)
    com = obj_world @ np.array([cx, cy, 0.0, 1.0])
    lever = float(np.hypot(*(com[:2] - tcp_world[:2, 3])))
    return t.mass * 9.81 * lever
