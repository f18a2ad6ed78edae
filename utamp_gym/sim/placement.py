"""Where a held object goes down: the spot on its support and the arm's path to it.

On an object, the centre of its usable surface (`decode.support_point`), unless a member of
the object would then lie beyond the hand's reach from above (`TOP_DOWN_REACH`), where the arm
could not pick it up again (a tray set on a utensil at the table's far edge). On a table slot, a
spot where the object lies inside the slot's region with every member's centre within
`MEMBER_REACH` of the robot's base, which is what the rules grant a slot
(`symbolic.slots.admits`): the slot's position or, when that leaves no room (a neighbour,
the arm's reach), the nearest such spots within `SPOT_RADIUS` of it (`_slot_spots`), then the
rest of the slot's; in each group, those that leave every other object `SPOT_GAP` first.
Over an object the held object is let go higher when the fingers would meet the support at
the usual drop (`PLACE_DROPS`). `plan_place` returns the path from the place pose up to the
pre-place pose, or raises `GroundingError`; the place skill (`skills.place`) moves along it.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Iterator

import numpy as np

from utamp_gym.errors import GroundingError
from utamp_gym.robot.kinematics import TOP_DOWN_REACH
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import Box
from utamp_gym.sim import relook
from utamp_gym.sim.control import LinePath, allowing
from utamp_gym.sim.decode import (
    PLACE_DROP,
    MacroAction,
    hand_for_object,
    place_object_pose,
    support_point,
    world_aabb,
    yaw_of,
)
from utamp_gym.sim.measure import Held, SimState, SkillFailure
from utamp_gym.symbolic.slots import (
    MEMBER_REACH,
    SPOT_STEP,
    beyond_reach_cm,
    slot_spots,
    usable_region,
)

PREPLACE = 0.10  # m above the place pose
#: a placement on a table slot tries its position, then spots `SPOT_STEP` apart within this
#: radius of it (`_slot_spots`)
SPOT_RADIUS = 0.09  # m
#: m: spots that leave this much room to every other object come first (a tumbler set down
#: 1 mm from another could not be lifted past it later)
SPOT_GAP = 0.04
#: m above an object support a held object is released at, in turn: a plate held by its rim
#: over a plate whose rim rises around it would put a finger 4 mm into the lower rim at the
#: usual `PLACE_DROP`; it is let go 1-2 cm higher and falls into the lower plate's well
PLACE_DROPS = (PLACE_DROP, PLACE_DROP + 0.01, PLACE_DROP + 0.02)


def _slot_spots(st: SimState, slot: str, radius: float = SPOT_RADIUS) -> list[np.ndarray]:
    """Where on the table slot `slot` an object's footprint centre may go, best first: the
    slot's position, then the slot's spots (`symbolic.slots.slot_spots`) within `radius` of
    it, nearest first. A stack beside the slot, or the arm's reach, may leave no room at the
    position itself (a plate's rim over a neighbour's wall); a person would put it a few
    centimetres along."""
    scene = st.world.scene
    spec = next(s for s in scene.slots if s.name == slot)
    px, py = spec.position
    return [
        np.array([x, y, 0.0])
        for x, y in slot_spots(scene, spec)
        if math.hypot(x - px, y - py) <= radius + 1e-9
    ]


def _world_box(t: ObjectType, pose: np.ndarray) -> Box:
    """The world-aligned box around an object of type `t` at `pose`."""
    lo, hi = world_aabb(t.bbox, pose)
    return Box(tuple(map(float, lo)), tuple(map(float, hi)))


def _footprints(st: SimState, exclude: str) -> list[Box]:
    """The boxes around every object but `exclude`, as the robot believes them."""
    scene = st.world.scene
    return [
        _world_box(scene.type_of(name), st.estimate(name))
        for name in st.world.body_ids
        if name != exclude
    ]


def _crowded(t: ObjectType, pose: np.ndarray, others: list[Box]) -> bool:
    """Whether an object of type `t` at `pose` would stand nearer than `SPOT_GAP` to another."""
    mine = _world_box(t, pose)
    return any(mine.gap_xy(other) < SPOT_GAP for other in others)


def _member_centres(t: ObjectType, pose: np.ndarray) -> dict[str, tuple[float, float]]:
    """World x, y of each member centre of an object of type `t` at `pose`, by member name
    (the robot's base is the world origin)."""
    centres = {}
    for name, m in t.members.items():
        x, y = pose[:2, :3] @ np.asarray(m.box.center, dtype=float) + pose[:2, 3]
        centres[name] = (float(x), float(y))
    return centres


def _beyond_reach(t: ObjectType, pose: np.ndarray) -> float:
    """How far (cm, rounded) the farthest member centre of an object of type `t` at `pose`
    lies beyond `MEMBER_REACH` of the robot's base; 0 within it."""
    return beyond_reach_cm(_member_centres(t, pose).values())


def _out_of_hand_reach(t: ObjectType, pose: np.ndarray) -> tuple[str, float] | None:
    """The member of an object of type `t` at `pose` whose centre lies farthest from the
    robot's base, and that distance (m), if it is beyond `TOP_DOWN_REACH`; else None."""
    dist, member = max((math.hypot(*xy), name) for name, xy in _member_centres(t, pose).items())
    return (member, dist) if dist > TOP_DOWN_REACH else None


def _slot_targets(
    st: SimState, name: str, slot: str, now: np.ndarray, near: list[np.ndarray], n_near: int,
    base_yaw: float,
) -> Iterator[np.ndarray]:  # fmt: skip
    """Place poses of `name` on a table slot where it lies inside the slot's usable region with
    every member's centre within `MEMBER_REACH`, as the rules grant a slot
    (`symbolic.slots.admits`): of `near` (at its first `n_near` spots) first, then at the rest
    of the slot's spots, posed only when every near one has failed; in each group, those that
    leave a finger room first."""
    scene = st.world.scene
    t = scene.type_of(name)
    region = usable_region(scene, next(s for s in scene.slots if s.name == slot))
    others = _footprints(st, exclude=name)

    def admissible(group: Iterable[np.ndarray]) -> list[np.ndarray]:
        ok = [
            target
            for target in group
            if region.contains_xy(_world_box(t, target), tol=1e-6) and _beyond_reach(t, target) == 0
        ]
        return sorted(ok, key=lambda target: _crowded(t, target, others))

    yield from admissible(near)
    rest = _slot_spots(st, slot, math.inf)[n_near:]
    yield from admissible(
        place_object_pose(t, now, spot, yaw=yaw)
        for spot, yaw in itertools.product(rest, (base_yaw, None))
    )


def _support_surfaces(st: SimState, act: MacroAction) -> list[np.ndarray]:
    """Where the held object's footprint may be centred on its support, best first: on an
    object, the centre of its usable surface; on a slot, `_slot_spots`."""
    scene = st.world.scene
    if act.support in st.world.slot_positions:
        return _slot_spots(st, act.support)
    if act.support not in st.world.body_ids:
        valid = [*st.world.body_ids, *st.world.slot_positions]
        raise GroundingError(f"unknown support '{act.support}'; valid: {', '.join(valid)}")
    try:
        pose = st.estimate(act.support)
        return [support_point(scene.type_of(act.support), act.support_part, pose)]
    except GroundingError as exc:
        raise SkillFailure(f"cannot place {act.grasp.obj} on {act.support}: {exc}") from None


def plan_place(
    st: SimState, held: Held, act: MacroAction, carry_z: float | None = None
) -> LinePath:
    """Path from the place configuration up to the pre-place one, or `GroundingError`.

    The object turns square to its support (its yaw); if that does not fit, it keeps its
    current yaw. With `carry_z` the pre-place pose is raised to that TCP height where the
    line allows (the height the object was carried at: it comes over the support as high
    as it was lifted, above every other object, and then goes down).
    """
    name, arm = held.obj, st.arm
    t, now = st.world.scene.type_of(name), arm.tcp() @ held.belief
    surfaces = _support_surfaces(st, act)
    base_yaw = yaw_of(st.estimate(act.support)[:3, :3]) if act.support in st.world.body_ids else 0.0
    tried, posed = [], False
    near = arm.sync(arm.near, gap=arm.gap())
    near.attach(held.body, held.belief)
    world = st.world
    support = world.geom_ids.get(act.support, [world.table_geom_id])
    # lowering into a snug support (a board into a rimmed tray) may graze it: touching is
    # allowed there, and penetrating (in the robot's belief) as far as the estimates' error
    # allows (`relook.PLACE_ROOM_SIGMAS`); the guarded descent and the close look at the
    # support (`relook.aim_place`) take care of the rest
    try:
        with allowing(near, world.geom_ids[name], support, relook.place_room(st)):
            # square to the support first, else as held; on a slot, nearest its position; on
            # an object, released higher if the fingers would meet it (`PLACE_DROPS`)
            drops = (PLACE_DROP,) if act.support not in world.body_ids else PLACE_DROPS
            targets: Iterable[np.ndarray] = [
                place_object_pose(t, now, surface, yaw=yaw, drop=drop)
                for drop, surface, yaw in itertools.product(drops, surfaces, (base_yaw, None))
            ]
            if act.support in world.slot_positions:  # lazily: the whole slot only if needed
                targets = _slot_targets(
                    st, name, act.support, now, list(targets), len(surfaces), base_yaw
                )
            else:  # on an object: never where the arm could not pick it up again
                beyond = [(target, _out_of_hand_reach(t, target)) for target in targets]
                if all(far is not None for _, far in beyond):
                    member, dist = min((far for _, far in beyond if far), key=lambda f: f[1])
                    raise GroundingError(
                        f"{name} on {act.support} would put {name}-{member} {dist:.2f} m from "
                        f"the robot's base, beyond the hand's reach from above "
                        f"({TOP_DOWN_REACH} m): the arm could not pick it up again"
                    )
                targets = [target for target, far in beyond if far is None]
            for target in targets:
                posed = True
                tcp = hand_for_object(target, held.belief)
                high = PREPLACE if carry_z is None else max(PREPLACE, carry_z - tcp[2, 3])
                for q in arm.ik_solutions(tcp, near.is_valid):
                    for rise in dict.fromkeys((high, PREPLACE)):
                        try:
                            return arm.line(
                                q,
                                tcp,
                                np.array([0.0, 0.0, rise]),
                                near.is_valid,
                                what=f"lowering {name} onto {act.support}",
                            )
                        except GroundingError as exc:
                            tried.append(str(exc))
                tried.append("no collision-free IK solution")
    finally:
        near.detach()
    if not posed:  # on a slot: no spot holds it (the rules do not grant it the slot either)
        raise GroundingError(
            f"no spot of {act.support} holds {name}: none leaves its footprint inside the "
            f"slot's region with every member within {MEMBER_REACH} m of the robot's base"
        )
    raise GroundingError(
        f"IK infeasible: cannot put {name} on {act.support} ({'; '.join(dict.fromkeys(tried))})"
    )


__all__ = [
    "MEMBER_REACH",
    "PLACE_DROPS",
    "PREPLACE",
    "SPOT_GAP",
    "SPOT_RADIUS",
    "SPOT_STEP",
    "TOP_DOWN_REACH",
    "plan_place",
]
