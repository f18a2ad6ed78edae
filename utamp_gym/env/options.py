"""Keyword options of the kitchen envs, validated up front with messages that list valid values.

Why one frozen dataclass: every option is checked once, in one place, before anything is
grounded or simulated, and the env, the universe cache key and the docs read the same fields.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from utamp_gym.affordances.sources import AFFORDANCE_SOURCES, DEFAULT_NOISE
from utamp_gym.backend import (
    DEFAULT_BACKEND,
    DEFAULT_PERCEPTION,
    DEFAULT_POSE_NOISE,
    MAX_POSE_NOISE,
    PERCEPTION_MODES,
)
from utamp_gym.env.goals import Task, check_task
from utamp_gym.env.object_space import INTERFACES, MAX_OBJECTS, MAX_SLOTS
from utamp_gym.errors import UnknownNameError, UtampError
from utamp_gym.scene.model import BuiltScene, Scene
from utamp_gym.suites import (
    ALL_SUITES,
    GOAL_SUITES,
    PROCEDURAL,
    PROCEDURAL_SUITES,
    resolve_scene,
    suite_scenes,
)
from utamp_gym.symbolic.problem import DOMAINS
from utamp_gym.symbolic.universe import UniverseKey

GROUNDINGS = ("physics", "symbolic")
#: see `utamp_gym.env.viewer` for what each mode shows
RENDER_MODES = ("rgb_array", "rgb_array_list", "human")
#: what `action_masks()` allows: U-TAMP-2 preconditions under the env's affordances, the
#: U-TAMP-1 object-centric (geometric) preconditions only, or every action of the scene
MASKS = ("affordances", "geometric", "none")
MIN_OBJECTS = 2


def _bool(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return value


def _choice(kind: str, value: Any, valid: Sequence[str]) -> str:
    if not isinstance(value, str) or value not in valid:
        raise UnknownNameError(kind, str(value), valid)
    return value


def _unit(name: str, value: Any, high: float = 1.0) -> float:
    """A finite number in [0, high]."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value <= high:
        raise ValueError(f"{name} must be a number in [0, {high:g}], got {value!r}")
    return float(value)


def packaged(scene: Scene) -> bool:
    """Whether `scene` is the suite or packaged scene its name names (field by field)."""
    try:
        return resolve_scene(scene.name) == scene
    except (UtampError, OSError):  # no such name (or no readable file of it)
        return False


def _size(name: str, value: Any) -> tuple[int, int]:
    """(height, width) in pixels; an int means a square."""
    pair = (value, value) if isinstance(value, int) and not isinstance(value, bool) else value
    ok = (
        isinstance(pair, Sequence)
        and len(pair) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) and 8 <= v <= 4096 for v in pair)
    )
    if not ok:
        raise ValueError(f"{name} must be (height, width) in pixels, each 8..4096, got {value!r}")
    return int(pair[0]), int(pair[1])


@dataclass(frozen=True)
class EnvOptions:
    """Options of `UTampKitchenEnv` (documented in its class docstring)."""

    suite: str | None
    objects: tuple[str, ...]
    grounding: str = "physics"
    domain: str = "utamp2"
    affordances: str = "gt"
    noise: float = DEFAULT_NOISE
    num_objects: int | None = None
    scene: str | Scene | None = None
    terminate_on_failure: bool = False
    reward_shaping: bool = False
    render_mode: str | None = None
    camera: bool = False
    image_size: tuple[int, int] = (84, 84)
    render_size: tuple[int, int] = (480, 480)
    backend: str | Callable[..., Any] = DEFAULT_BACKEND
    backend_kwargs: Mapping[str, Any] = field(default_factory=dict)
    record_timings: bool = False
    masks: str = "affordances"
    disturbance: float = 0.0
    pose_noise: float = DEFAULT_POSE_NOISE
    split: str | None = None
    perception: str = DEFAULT_PERCEPTION
    interface: str = "grounded"
    task: Task = None
    goal_observation: bool = False
    slots: int | None = None

    def __post_init__(self) -> None:
        if self.split is not None:  # "train", "procedural-v1/train" or "procedural-v2/train"
            splits = [s.removeprefix(f"{PROCEDURAL}/") for s in PROCEDURAL_SUITES]
            short = str(self.split).removeprefix(f"{PROCEDURAL}/")
            _choice("split", short, [*splits, *GOAL_SUITES])
            suite = short if short in GOAL_SUITES else f"{PROCEDURAL}/{short}"
            if self.suite is not None and self.suite != suite:
                raise ValueError(
                    f"split={self.split!r} is the suite {suite!r}; drop suite={self.suite!r}"
                )
            object.__setattr__(self, "split", short)
            object.__setattr__(self, "suite", suite)
        if self.suite is not None:
            _choice("suite", self.suite, ALL_SUITES)
        if self.suite is None and self.scene is None:
            raise ValueError("an env needs a suite or a scene")
        names = self.objects
        if (
            isinstance(names, str)
            or not isinstance(names, Sequence)
            or not names
            or len(set(names)) != len(names)
            or not all(isinstance(n, str) for n in names)
        ):
            raise ValueError(f"objects must be a sequence of distinct object names, got {names!r}")
        _choice("grounding", self.grounding, GROUNDINGS)
        _choice("domain", self.domain, DOMAINS)
        _choice("affordance source", self.affordances, AFFORDANCE_SOURCES)
        _unit("noise", self.noise)
        _choice("masks", self.masks, MASKS)
        _choice("interface", self.interface, INTERFACES)
        check_task(self.task)
        _bool("goal_observation", self.goal_observation)
        if self.masks != "affordances" and self.domain != "utamp2":
            raise ValueError(
                f"masks={self.masks!r} needs domain='utamp2' (it drops U-TAMP-2's affordance "
                f"preconditions); domain {self.domain!r} has none, use masks='affordances'"
            )
        object.__setattr__(self, "disturbance", _unit("disturbance", self.disturbance))
        if self.disturbance > 0 and self.grounding != "physics":
            raise ValueError("disturbance needs grounding='physics' (faults are physical)")
        object.__setattr__(
            self, "pose_noise", _unit("pose_noise (m)", self.pose_noise, MAX_POSE_NOISE)
        )
        _choice("perception", self.perception, PERCEPTION_MODES)
        most = MAX_SLOTS if self.interface == "objects" else len(names)  # objects: rows grow
        if self.num_objects is not None and (
            isinstance(self.num_objects, bool)
            or not isinstance(self.num_objects, int)
            or not MIN_OBJECTS <= self.num_objects <= most
        ):
            raise ValueError(
                f"num_objects must be an integer in {MIN_OBJECTS}..{most} or None, "
                f"got {self.num_objects!r}"
            )
        if self.slots is not None and (
            self.interface != "objects"
            or isinstance(self.slots, bool)
            or not isinstance(self.slots, int)
            or not MIN_OBJECTS <= self.slots <= MAX_SLOTS
        ):
            raise ValueError(
                f"slots (the objects interface's object slots) must be None or an integer in "
                f"{MIN_OBJECTS}..{MAX_SLOTS} with interface='objects', got {self.slots!r}"
            )
        if self.scene is not None and not isinstance(self.scene, str | Scene):
            raise ValueError(f"scene must be a scene name, a path or a Scene, got {self.scene!r}")
        if isinstance(self.scene, Scene) and packaged(self.scene):  # its name says it all
            object.__setattr__(self, "scene", self.scene.name)
        _bool("terminate_on_failure", self.terminate_on_failure)
        _bool("reward_shaping", self.reward_shaping)
        _bool("camera", self.camera)
        _bool("record_timings", self.record_timings)
        if self.render_mode is not None:
            _choice("render_mode", self.render_mode, RENDER_MODES)
        object.__setattr__(self, "objects", tuple(names))
        object.__setattr__(self, "image_size", _size("image_size", self.image_size))
        object.__setattr__(self, "render_size", _size("render_size", self.render_size))
        if not isinstance(self.backend_kwargs, Mapping):
            raise ValueError(f"backend_kwargs must be a mapping, got {self.backend_kwargs!r}")
        if not (callable(self.backend) or isinstance(self.backend, str)):
            raise ValueError(f"backend must be 'module:Class' or a callable, got {self.backend!r}")

    # ------------------------------------------------------------------ derived
    def universe_key(self) -> UniverseKey:
        """The action universe: the whole suite (plus a fixed scene from outside it); for a
        procedural split, every split of its version (one action space for all of them).

        It ignores `num_objects` and a fixed suite `scene`, so those options keep the action
        and observation spaces of the env id (useful for curricula). A `Scene` built in code
        (one that is not the packaged scene of its name) is never the suite's: it joins the
        universe by its content (`BuiltScene`), whatever its name.
        """
        scene = self.scene
        if self.suite in PROCEDURAL_SUITES:  # every split shares one action space
            suite: str | None = PROCEDURAL
            in_suite = scene is None or (
                isinstance(scene, str) and scene.startswith(f"{PROCEDURAL}/")
            )
        else:
            suite = self.suite
            in_suite = (
                self.suite is not None
                and isinstance(scene, str)
                and scene in {s.name for s in suite_scenes(self.suite)}
            )
        extra: tuple[str | BuiltScene, ...] = ()
        if scene is not None and not in_suite:
            extra = (BuiltScene(scene) if isinstance(scene, Scene) else scene,)
        if self.masks != "affordances":  # "geometric" and "none" share one action space
            return UniverseKey(self.domain, "none", suite, extra, "geometric")
        affordances = "none" if self.domain == "utamp1" else self.affordances
        return UniverseKey(self.domain, affordances, suite, extra)

    def scenes(self) -> tuple[Scene, ...]:
        """The scenes episodes are sampled from (one if `scene` is set)."""
        if self.scene is not None:
            one = self.scene if isinstance(self.scene, Scene) else resolve_scene(self.scene)
            chosen: tuple[Scene, ...] = (one,)
            if self.num_objects is not None and one.n_objects != self.num_objects:
                raise ValueError(
                    f"scene '{one.name}' has {chosen[0].n_objects} objects, "
                    f"but num_objects={self.num_objects}"
                )
        else:
            assert self.suite is not None
            pool = suite_scenes(self.suite)
            chosen = tuple(
                s for s in pool if self.num_objects is None or s.n_objects == self.num_objects
            )
            if not chosen:
                counts = sorted({s.n_objects for s in pool})
                raise ValueError(
                    f"suite '{self.suite}' has no scene with {self.num_objects} objects; "
                    f"valid num_objects: {', '.join(map(str, counts))}"
                )
        for s in chosen:
            extra = [n for n in s.object_names if n not in self.objects]
            if extra and self.interface != "objects":  # its rows grow to fit (`fitted`)
                raise ValueError(
                    f"scene '{s.name}' has objects {extra} outside the env's observation rows "
                    f"{list(self.objects)}"
                )
        return chosen

    def fitted(self, scenes: Sequence[Scene]) -> EnvOptions:
        """These options for the env's `scenes`: with the objects interface, whose spaces do
        not show the pose rows, the rows grow by the scenes' other object names, and
        ``slots`` None becomes `MAX_OBJECTS` or the most objects of a scene if more (a
        larger ``slots`` than a scene has leaves slots empty; a smaller one is refused)."""
        if self.interface != "objects":
            return self
        names = dict.fromkeys(self.objects)
        names.update(dict.fromkeys(n for s in scenes for n in s.object_names))
        most = max((s.n_objects for s in scenes), default=0)
        if self.slots is not None and most > self.slots:
            big = next(s for s in scenes if s.n_objects == most)
            raise ValueError(
                f"scene '{big.name}' has {most} objects, more than slots={self.slots}: use "
                f"slots={most} or more (or None: as many as the largest scene)"
            )
        slots = self.slots if self.slots is not None else max(MAX_OBJECTS, most)
        return replace(self, objects=tuple(names), slots=slots)


def action_id(action: Any, n: int) -> int:
    """An env action as an int in ``[0, n)``, else `ValueError` (common cases checked first)."""
    if type(action) not in (int, np.int64):
        if isinstance(action, np.ndarray) and action.size == 1 and action.dtype.kind in "iu":
            action = action.reshape(())[()]
        if isinstance(action, bool | np.bool_) or not isinstance(action, int | np.integer):
            raise ValueError(
                f"action must be an integer id in [0, {n}), got {action!r}; to act with "
                "PDDL strings wrap the env in utamp_gym.env.wrappers.SymbolicActionWrapper"
            )
    if not 0 <= action < n:
        raise ValueError(f"action {int(action)} is out of range [0, {n})")
    return int(action)
