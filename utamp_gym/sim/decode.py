"""Decode U-TAMP-2 macro-action symbols into hand and object poses (pure functions).

As in the paper, a grasp is decoded from the *current* pose of the object and the
bounding box of the grasped member: the approach (TCP z) points against the outward
normal of the palm part, the finger-opening axis (TCP y) lies along the normal of the
first finger part, and the TCP sits at the member's middle, `GRASP_DEPTH` (or half the
member) below its palm face. A placement puts the held object's footprint centre over
the centre of the support's usable surface, resting on it ("at the support's
centroid"), with the object's current yaw. A slide moves the object's footprint
centre onto the free space's centre. Poses are 4x4 matrices in the world frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from utamp_gym.errors import GroundingError, UnknownNameError
from utamp_gym.robot.kinematics import quat_wxyz_to_matrix
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.geometry import NORMALS, SIDES, Box, axis_of
from utamp_gym.scene.model import Scene
from utamp_gym.scene.shapes import rim_strip
from utamp_gym.sim.bodies import object_prims

GRASP_DEPTH = 0.025  # m, deepest grasp below the member's palm face
PREGRASP = 0.10  # m, pre-grasp distance back along the approach
TIP_BELOW_TCP = 0.0095  # m, Panda finger pads reach this far past the TCP along the approach
TIP_CLEARANCE = 0.003  # m, fingertips stay this far above the surface the object stands on
FINGER_CLEARANCE = 0.008  # m, pre-grasp opening beyond the member's width, per side
MAX_OPENING = 0.08  # m, Panda hand fully open
PLACE_DROP = 0.004  # m, a placed object is released this far above its support
ACTIONS = ("pick-support", "place-support", "slide-support", "slide-edge", "place-edge")
#: slide-edge and place-edge (the extended domain ``utamp2x``): a pick's and a place's symbols
ARITY = {
    "pick-support": 10,
    "place-support": 11,
    "slide-support": 13,
    "slide-edge": 10,
    "place-edge": 11,
}


@dataclass(frozen=True)
class GraspSymbols:
    """Which member is grasped, palm part and finger parts (object-frame parts)."""

    obj: str
    member: str  # member name in the object type (symbol without the "<obj>-" prefix)
    palm: str
    finger1: str
    finger2: str


@dataclass(frozen=True)
class MacroAction:
    """A parsed macro action: `kind` is the PDDL action name; unused fields are ""."""

    kind: str
    grasp: GraspSymbols
    support: str  # what the object rests on before (pick, slide) or after (place)
    support_part: str = "on"  # place: the support's part the object is put on
    space: str = ""  # slide: the free space to slide into
    text: str = ""


@dataclass(frozen=True)
class GraspPose:
    """A decoded grasp: TCP pose at grasp and pre-grasp, opening before closing (m)."""

    tcp: np.ndarray
    pregrasp: np.ndarray
    opening: float
    width: float  # member extent between the fingers (m)


# ----------------------------------------------------------------- parsing
def parse_action(action: str, scene: Scene) -> MacroAction:
    """Parse a grounded PDDL action against the scene; raises on unknown names/arity."""
    tokens = action.strip().strip("()").split()
    if not tokens or tokens[0] not in ARITY:
        raise UnknownNameError("action", tokens[0] if tokens else action, ACTIONS)
    kind, args = tokens[0], [t.lower() for t in tokens[1:]]
    if len(args) != ARITY[kind]:
        raise GroundingError(f"'{action}': {kind} takes {ARITY[kind]} arguments, got {len(args)}")
    obj, mem_symbol = args[0], args[1]
    t = scene.type_of(obj)
    member = mem_symbol.removeprefix(f"{obj}-")
    if member not in t.members:
        valid = [f"{obj}-{m}" for m in t.members]
        raise UnknownNameError(f"member of {obj}", mem_symbol, valid)
    for part in args[2:5]:
        if part not in SIDES:
            raise UnknownNameError("part", part, SIDES)
    grasp = GraspSymbols(obj, member, args[2], args[3], args[4])
    if axis_of(grasp.palm) == axis_of(grasp.finger1):
        raise GroundingError(f"'{action}': palm part and finger part lie on the same axis")
    if kind in ("pick-support", "slide-edge"):
        return MacroAction(kind, grasp, support=args[7], text=action)
    if kind in ("place-support", "place-edge"):
        return MacroAction(kind, grasp, support=args[8], support_part=args[10], text=action)
    return MacroAction(kind, grasp, support=args[6], space=args[9], text=action)


# ----------------------------------------------------------------- frames
def pose_of(position: np.ndarray, quat_wxyz: np.ndarray) -> np.ndarray:
    """4x4 pose from a position and a wxyz quaternion."""
    out = np.eye(4)
    out[:3, :3] = quat_wxyz_to_matrix(np.asarray(quat_wxyz, dtype=float))
    out[:3, 3] = position
    return out


def box_corners(box: Box) -> np.ndarray:
    """The 8 corners (8, 3) of an axis-aligned box."""
    lo, hi = np.asarray(box.min), np.asarray(box.max)
    return np.array([[(lo, hi)[(k >> i) & 1][i] for i in range(3)] for k in range(8)])


def world_aabb(box: Box, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World axis-aligned bounds of an object-frame box at `pose`."""
    pts = box_corners(box) @ pose[:3, :3].T + pose[:3, 3]
    return pts.min(axis=0), pts.max(axis=0)


def footprint_centre(t: ObjectType, pose: np.ndarray) -> np.ndarray:
    """World xy of the object's bounding-box centre (its footprint centre when upright)."""
    return (pose[:3, :3] @ t.bbox.center + pose[:3, 3])[:2]


def _rot_z(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def yaw_of(rot: np.ndarray) -> float:
    """Heading (rad) of an upright or inverted object: the angle of its x axis."""
    return math.atan2(rot[1, 0], rot[0, 0])


def rectified_rotation(rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rotation, orientation-only rotation): upright or inverted with the current yaw."""
    orient = np.eye(3) if rot[2, 2] >= 0 else np.diag([1.0, -1.0, -1.0])
    return _rot_z(yaw_of(rot)) @ orient, orient


# ----------------------------------------------------------------- grasp
def _prim_bounds(t: ObjectType, member: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """Object-frame bounds of the collision primitives realising `member`."""
    out = []
    for p in object_prims(t):
        if p.member != member:
            continue
        half = np.array([p.size[0], p.size[0], p.size[1]]) if p.shape == "cylinder" else p.size
        rot = quat_wxyz_to_matrix(np.asarray(p.quat))
        ext = np.abs(rot) @ np.asarray(half)
        out.append((np.asarray(p.pos) - ext, np.asarray(p.pos) + ext))
    return out


def grasp_point(t: ObjectType, member: str, palm: str, finger: str) -> np.ndarray:
    """Object-frame TCP position: member middle, `GRASP_DEPTH` below the palm face.

    If the member's middle is hollow at that depth (a loop handle), the point moves
    along the remaining lateral axis to the nearest solid primitive of the member. A body
    too wide for the hand with an open top is pinched at its wall on `finger`'s side
    (`utamp_gym.scene.shapes.rim_strip`): the point is that strip's.
    """
    strip = rim_strip(t, member, palm, finger)
    if strip is not None:
        lo, hi = np.asarray(strip.min), np.asarray(strip.max)
        point = (lo + hi) / 2
        point[2] = hi[2] - min(GRASP_DEPTH, (hi[2] - lo[2]) / 2)
        return point
    box = t.members[member].box
    lo, hi = np.asarray(box.min), np.asarray(box.max)
    point = (lo + hi) / 2
    ax = axis_of(palm)
    sign = NORMALS[palm][ax]
    depth = min(GRASP_DEPTH, (hi[ax] - lo[ax]) / 2)
    point[ax] = (hi[ax] if sign > 0 else lo[ax]) - sign * depth
    lateral = 3 - ax - axis_of(finger)
    solid = [
        (plo, phi)
        for plo, phi in _prim_bounds(t, member)
        if plo[ax] - 1e-9 <= point[ax] <= phi[ax] + 1e-9
    ]
    if solid and not any(plo[lateral] <= point[lateral] <= phi[lateral] for plo, phi in solid):
        centres = [(plo[lateral] + phi[lateral]) / 2 for plo, phi in solid]
        point[lateral] = min(centres, key=lambda c: abs(c - point[lateral]))
    return point


def grasp_candidates(
    t: ObjectType, symbols: GraspSymbols, obj_pose: np.ndarray, *, prefer_x: np.ndarray
) -> list[GraspPose]:
    """The two grasps (finger axis sign ±) for the symbols, closest to `prefer_x` first.

    `prefer_x` is a world direction the TCP x axis should follow (e.g. the current
    hand's), so the wrist turns as little as possible. The fingertips are kept
    `TIP_CLEARANCE` above the lowest point of the object (the surface it stands on).
    """
    rot = obj_pose[:3, :3]
    approach = -rot @ np.asarray(NORMALS[symbols.palm], dtype=float)
    finger = rot @ np.asarray(NORMALS[symbols.finger1], dtype=float)
    finger -= (finger @ approach) * approach
    if np.linalg.norm(finger) < 1e-6:
        raise GroundingError(f"{symbols.obj}: finger part is parallel to the approach")
    finger /= np.linalg.norm(finger)
    point = obj_pose[:3, :3] @ grasp_point(t, symbols.member, symbols.palm, symbols.finger1)
    point += obj_pose[:3, 3]
    if approach[2] < -0.5:  # from above: fingertips must not reach the support
        bottom = world_aabb(t.bbox, obj_pose)[0][2]
        point[2] = max(point[2], bottom + TIP_CLEARANCE - approach[2] * TIP_BELOW_TCP)
    strip = rim_strip(t, symbols.member, symbols.palm, symbols.finger1)
    box = t.members[symbols.member].box if strip is None else strip
    width = float(box.size[axis_of(symbols.finger1)])
    opening = min(MAX_OPENING, width + 2 * FINGER_CLEARANCE)
    out = []
    for y in (finger, -finger):
        tcp = np.eye(4)
        tcp[:3, :3] = np.column_stack([np.cross(y, approach), y, approach])
        tcp[:3, 3] = point
        pre = tcp.copy()
        pre[:3, 3] = point - PREGRASP * approach
        out.append(GraspPose(tcp, pre, opening, width))
    out.sort(key=lambda g: -float(g.tcp[:3, 0] @ prefer_x))
    return out


# ----------------------------------------------------------------- place and slide
def support_point(t: ObjectType, part: str, pose: np.ndarray) -> np.ndarray:
    """World centre of the usable surface of `part` of an object at `pose`.

    Raises `GroundingError` if that part does not face up (nothing can rest on it).
    """
    normal = pose[:3, :3] @ np.asarray(NORMALS[part], dtype=float)
    if part not in ("on", "under") or normal[2] < 0.9:
        raise GroundingError(f"part '{part}' does not face up (normal {np.round(normal, 2)})")
    cx, cy = t.surface_center(part)
    return pose[:3, :3] @ np.array([cx, cy, t.surface_height(part)]) + pose[:3, 3]


def place_object_pose(
    t: ObjectType,
    obj_pose: np.ndarray,
    surface: np.ndarray,
    *,
    yaw: float | None = None,
    drop: float = PLACE_DROP,
) -> np.ndarray:
    """Target pose of a held object: footprint centred on `surface`, resting on it.

    The object is squared up to upright or inverted and keeps its current yaw (or
    turns to `yaw`); its bounding box's bottom ends `drop` above the surface.
    """
    rot, orient = rectified_rotation(obj_pose[:3, :3])
    if yaw is not None:
        rot = _rot_z(yaw) @ orient
    bottom = float((box_corners(t.bbox) @ orient.T)[:, 2].min())  # yaw keeps heights
    out = np.eye(4)
    out[:3, :3] = rot
    out[:2, 3] = surface[:2] - (rot @ t.bbox.center)[:2]
    out[2, 3] = surface[2] - bottom + drop
    return out


def hand_for_object(obj_target: np.ndarray, tcp_t_obj: np.ndarray) -> np.ndarray:
    """TCP pose that puts a rigidly held object (held at `tcp_t_obj`) at `obj_target`."""
    return obj_target @ np.linalg.inv(tcp_t_obj)


def slide_vector(t: ObjectType, obj_pose: np.ndarray, space_xy: np.ndarray) -> np.ndarray:
    """Horizontal world displacement taking the footprint centre onto the space centre."""
    delta = np.asarray(space_xy, dtype=float) - footprint_centre(t, obj_pose)
    return np.array([delta[0], delta[1], 0.0])


__all__ = [
    "GraspPose",
    "GraspSymbols",
    "MacroAction",
    "footprint_centre",
    "grasp_candidates",
    "grasp_point",
    "hand_for_object",
    "parse_action",
    "place_object_pose",
    "pose_of",
    "rectified_rotation",
    "slide_vector",
    "support_point",
    "world_aabb",
    "yaw_of",
]
