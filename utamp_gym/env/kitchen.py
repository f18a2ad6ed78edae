"""`UTampKitchenEnv`: organise a kitchen table (default: stack every object on the tray).

The dm_control split: `SymbolicState` (+ `SymbolicPoses`) or a `PhysicsBackend` is the
physics, `KitchenTask` the reward and termination, this class the Gymnasium glue.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from utamp_gym.affordances.sources import DEFAULT_NOISE
from utamp_gym.backend import (
    DEFAULT_BACKEND,
    DEFAULT_PERCEPTION,
    DEFAULT_POSE_NOISE,
    MacroResult,
    PhysicsBackend,
)
from utamp_gym.env.episode import RESET_OPTIONS, Episode, chosen_scene
from utamp_gym.env.goals import EpisodeGoals
from utamp_gym.env.grounding import make_grounding
from utamp_gym.env.info import StepRecord
from utamp_gym.env.objects import ObjectInterface
from utamp_gym.env.observe import Obs, Observer
from utamp_gym.env.options import EnvOptions, action_id
from utamp_gym.env.physics import NOT_RUN, Stepped
from utamp_gym.env.task import KitchenTask
from utamp_gym.env.viewer import FRAME_RATE, Rendering
from utamp_gym.env.views import KitchenViews
from utamp_gym.symbolic.atoms import InitialAtoms
from utamp_gym.symbolic.state import SymbolicState
from utamp_gym.symbolic.universe import Universe, ground_universe
from utamp_gym.tasks.goal import Goal

#: observation rows of `object_poses` / `present`: the suites' catalogue objects
DEFAULT_OBJECTS = ("tray", "salt", "mug", "board", "pan")
__all__ = ["DEFAULT_OBJECTS", "RESET_OPTIONS", "Obs", "UTampKitchenEnv"]


class UTampKitchenEnv(KitchenViews, gym.Env[Obs, np.int64]):
    """A Franka Panda stacks every object of a kitchen table on the tray (U-TAMP-2 macro actions).

    Each episode samples a scene (uniformly, from the env's RNG) from the env's suite. The
    registered ids are defined by the files in ``envs/`` (one per id):
    ``UTampKitchen-v0`` (pick-place suite) and ``UTampKitchenSlide-v0`` (sliding suite).

    **Action space** – ``Discrete(n)`` over the ground macro actions (``pick-support``,
    ``place-support``, ``slide-support``) of the configuration's *universe*: the union of all
    scenes of the suite (plus a fixed scene from outside it), grounded once, sorted by PDDL
    string; `action_strings` lists them (see `utamp_gym.env.universe`). The order depends only
    on (suite, domain, affordance source, fixed out-of-suite scene), not on `num_objects`.
    `action_masks()` (sb3-contrib) and ``info["action_mask"]`` give the applicable ones:
    static preconditions (objects present, affordances) hold in the episode's scene and
    fluent ones in the current state. An action that is not an integer in ``[0, n)`` raises
    `ValueError`; a valid id whose precondition fails changes nothing and sets
    ``info["failure_reason"]`` to the first false precondition.

    **Observation space** – ``Dict``:

    * ``symbolic``: ``MultiBinary(m)``, the universe's fluent atoms in `symbolic_atoms` order;
    * ``object_poses``: ``Box((k, 7), float32)``, ``[x, y, z, qw, qx, qy, qz]`` of each of
      the `objects` rows (default tray, salt, mug, board, pan); absent objects are zeros;
    * ``present``: ``MultiBinary(k)``, which rows are in the scene;
    * ``robot``: ``Box((9,), float32)``, 7 arm joints (rad) + 2 fingers (m);
    * ``image`` (only with ``camera=True``): ``Box((h, w, 3), uint8)``.

    Symbolic grounding moves poses by the rules of `utamp_gym.env.poses` and keeps the robot
    at home; physics grounding reads both from the simulator. Both are backends behind one
    interface (`utamp_gym.env.grounding`): `backend` is the simulator or the
    `SymbolicBackend`.

    **Reward** – +1 on reaching the goal; ``reward_shaping=True`` adds +0.1 per goal literal
    newly holding (over the episode's best; the paper's tower goal: per object newly on the
    tower) and −0.01 per failed action (`utamp_gym.env.task`).

    **Goal** – `goal` (a `utamp_gym.tasks.goal.Goal`): the option ``task``, by default the
    scene's own goal (procedural-v2 scenes, scene files with ``[goal]``), else the paper's
    tower (every other suite: hand empty, every slot but the base's clear, so everything is
    one tower on the base); `instruction` is it in words (`utamp_gym.env.goals`).

    **Termination** – ``terminated`` at the goal: every goal literal holds (negated ones: their
    atom is false) in the symbolic state; in physics grounding in the measured state: the
    perceived atoms, with every object the goal is about perceived
    (`utamp_gym.tasks.success`). It also terminates at
    a dead end, when no action is applicable after a step (possible with noisy or rule-based
    affordances; an episode may even start at one, and then its first step terminates it),
    and in physics grounding when an object has no symbol (see below). With
    ``terminate_on_failure=True`` a failed action terminates too.
    ``truncated`` comes from Gymnasium's ``TimeLimit`` (``max_episode_steps`` of the env file,
    or ``gym.make(..., max_episode_steps=N)``).

    **Info** – one fixed structure of numbers, bools and strings from `reset` to the last
    step, so that dataset writers (Minari's ``DataCollector(env, record_infos=True)``) can
    stack it (`utamp_gym.env.info` documents every key and its earlier form): ``action``
    (PDDL string, ``""`` after reset), ``action_mask``, ``failure_reason`` (``""``: none),
    ``timings`` (empty unless ``record_timings=True``, so equal seeds give equal info;
    physics then: the macro's wall-clock phase times, ``perceive_s`` and ``step_s``),
    ``macro_result`` (a dict: executed, success, reason, retries; the `MacroResult` itself
    is `macro_result`), ``unexpected_atoms`` (one string; the list is `unexpected_atoms`),
    ``anomalies`` (every object -> its anomaly or ``""``), ``fault`` (``""``: none; see the
    closed loop below), ``scene`` (name), ``is_success`` (bool: the goal holds now, as for
    the reward; on every step and after reset, so it is there on the last step of every
    episode, where stable-baselines3's evaluation and the RL Zoo read it), ``goal`` (the
    goal's literals, a tuple of PDDL strings) and ``instruction`` (the goal in words; the
    tower's for suites without goals).

    **Options** (keyword arguments of ``gym.make``; each is validated up front):

    * ``suite`` (set by the env id: "pick-place", "sliding" or "extra") and ``objects`` (the
      rows of ``object_poses`` and ``present``; every object of every scene needs one);
    * ``grounding``: "physics" (default; the backend simulates every macro action) or
      "symbolic" (effects applied to the symbolic state, >20k steps/s);
    * ``domain``: "utamp2" | "utamp1" | "utamp2x" (U-TAMP-2 with the extended grasps,
      `utamp_gym.affordances.rim`); ``affordances``: "gt" | "rules" | "noisy" (re-detected
      every episode, each attribute wrong with probability ``noise``; utamp1 has none);
    * ``num_objects`` (2–5; 2–6 for procedural splits) restricts the scenes, ``scene`` fixes
      one (suite, packaged or file name, or a `utamp_gym.scene.model.Scene` built in code:
      no file is written; unless it is the packaged scene of its name it has an action
      universe and per-scene caches of its own, `Scene.key`, whatever its name);
      ``reset(options={"scene": name})`` picks the scene
      of one episode, ``reset(options={"world_seed": s})`` seeds its simulated world (the
      simulator's generator, and a second stream of it for injected faults; default: both
      from the env's RNG; the open-loop runner, `utamp_gym.agents.runs`, uses it);
    * ``split``: a procedural split ("train", "test-instances", "test-families", "test-count";
      `utamp_gym.suites.procedural`): its scenes instead of a suite's. All splits share one
      action universe and the observation rows ``base, obj1 .. obj5``
      (``UTampKitchenProcedural-v0``). A procedural-v2 split ("procedural-v2/test-tasks",
      `utamp_gym.suites.procedural_v2`; each scene with its goal) has an action universe of
      its own; its test-count scenes have up to 8 objects (the grounded interface needs the
      rows ``base, obj1 .. obj7``; the objects interface grows its slots, option ``slots``);
    * ``task``: the episodes' goal (`utamp_gym.env.goals`): None (default: the scene's own,
      else the paper's tower), a template id or composition (``"clear"``,
      ``"put-on+in-region"``: the scene's goal of that template, else one drawn per scene
      by a generator seeded from the scene's name; scenes with none are left out of
      `scenes`), or a `Goal` (a templated one rebuilt in each scene, a custom one as is);
    * ``goal_observation`` (default False, True in ``UTampKitchenGoals-v0``): the goal in the
      observation (`utamp_gym.env.object_goal`): in slot order with the objects interface
      (``goal_contact``, ``goal_free``, ``goal_not_contact``, ``goal_not_free``), over
      ``symbolic``'s atoms with the grounded one (``goal``, ``goal_not``);
    * ``terminate_on_failure``, ``reward_shaping``, ``render_mode`` (None | "rgb_array" |
      "rgb_array_list" | "human"), ``camera`` (adds ``image``), ``image_size`` /
      ``render_size`` ((height, width));
    * ``masks``: "affordances" (default: the U-TAMP-2 precondition under the env's affordances),
      "geometric" (U-TAMP-2 without affordance literals, over a larger action space that has
      e.g. side grasps and picks of the tray; `utamp_gym.env.geometric`) or "none" (that
      action space, every action whose objects are in the scene). Physics decides what the
      mask allows; symbolic grounding decides it with the outcome model
      (`utamp_gym.env.outcome`: the ground-truth U-TAMP-2 precondition; a failure names the
      false affordance);
    * ``interface``: "grounded" (default: the spaces above) or "objects" (object slots and a
      parametrised macro action, the same spaces for every scene: `utamp_gym.env.objects`;
      `action_strings` then names each index in slots, ``pick slot3 member0 grasp
      on/left/right``, and `action_pddl` (a) is the PDDL action stepping it runs now);
      ``slots``: its object slots (default None: 6, or the most objects of a scene of the
      env if more, e.g. 8 on procedural-v2's test-count; its pose rows grow to fit too);
    * physics only: ``backend`` ("module:Class" or a callable, built as
      ``backend(pose_noise=..., **backend_kwargs)``), ``record_timings`` (default False:
      wall-clock times in ``info["timings"]``), ``disturbance`` (fault probability per
      macro step, default 0), ``pose_noise`` (m, standard deviation of the robot's
      object-position estimates; `utamp_gym.backend`) and ``perception`` ("gaussian": the
      true pose plus ``pose_noise``; "rgbd": the poses and the perceived state's poses come
      from rendered RGB-D cameras, fitted by `utamp_gym.perception.tracking`; passed to the
      backend factory, `utamp_gym.grounding.physics_backend`, as ``perception=`` when not
      "gaussian").

    **Closed loop (physics grounding).** The symbolic state is never assumed: after `reset`
    and after every executed step (success or failure) it is *perceived* from the simulator
    (`utamp_gym.perception`), and ``symbolic``, `action_masks()`, ``info["action_mask"]``,
    `true_atoms()`, `static_atoms` (orientation atoms) and termination follow it. An action
    whose precondition is false in the perceived state fails fast with the reason, without
    reaching the simulator. ``info["unexpected_atoms"]`` lists, sorted, ``"+ATOM"`` (perceived,
    not predicted) and ``"-ATOM"`` (predicted by the action's effect, not perceived); it is
    empty when the step went as planned (always in symbolic grounding). An object with no
    symbol (toppled, fallen off the table, outside every slot, resting inside another object)
    has no atoms of its own, so no action involves it; ``info["anomalies"]`` maps it to the
    reason, and the episode terminates (the goal can no longer be reached).
    ``disturbance`` p: after each executed macro action, with probability p (from the env's
    RNG), one fault of `utamp_gym.backend.FAULT_KINDS` is injected; ``info["fault"]`` describes
    it (None otherwise).

    **Rendering** (`utamp_gym.env.viewer`) – "rgb_array": the simulator's camera in physics
    grounding, a labelled top-down schematic (`utamp_gym.env.render`) in symbolic grounding.
    "rgb_array_list": every frame since the last ``render()`` or ``reset()``; in physics
    grounding 10 frames per simulated second while macro actions run (``render_fps`` 10),
    so ``utamp_gym.env.video.RecordVideo`` records smooth videos. "human": a live MuJoCo
    viewer (physics) or a labelled matplotlib window (symbolic); it needs a display.

    **Version history** – v0: initial release; the option ``task``, `goal`, `instruction` and
    ``info["goal"]`` / ``info["instruction"]`` were added later without changing v0's spaces,
    rewards or the episodes of its default goal.
    """

    metadata = {  # noqa: RUF012
        "render_modes": ["rgb_array", "rgb_array_list", "human"],
        "render_fps": FRAME_RATE,  # per instance: 2 when there is one frame per macro action
    }

    def __init__(
        self,
        suite: str | None = None,
        objects: Sequence[str] = DEFAULT_OBJECTS,
        grounding: str = "physics",
        domain: str = "utamp2",
        affordances: str = "gt",
        noise: float = DEFAULT_NOISE,
        num_objects: int | None = None,
        scene: str | None = None,
        terminate_on_failure: bool = False,
        reward_shaping: bool = False,
        render_mode: str | None = None,
        camera: bool = False,
        image_size: int | tuple[int, int] = (84, 84),
        render_size: int | tuple[int, int] = (480, 480),
        backend: str | Callable[..., PhysicsBackend] = DEFAULT_BACKEND,
        backend_kwargs: Mapping[str, Any] | None = None,
        record_timings: bool = False,
        masks: str = "affordances",
        disturbance: float = 0.0,
        pose_noise: float = DEFAULT_POSE_NOISE,
        split: str | None = None,
        perception: str = DEFAULT_PERCEPTION,
        interface: str = "grounded",
        task: str | Goal | None = None,
        goal_observation: bool = False,
        slots: int | None = None,
    ) -> None:
        kwargs: dict[str, Any] = {
            "suite": suite, "objects": objects, "grounding": grounding, "domain": domain,
            "affordances": affordances, "noise": noise, "num_objects": num_objects,
            "scene": scene, "terminate_on_failure": terminate_on_failure,
            "reward_shaping": reward_shaping, "render_mode": render_mode, "camera": camera,
            "image_size": image_size, "render_size": render_size, "backend": backend,
            "backend_kwargs": dict(backend_kwargs or {}), "record_timings": record_timings,
            "masks": masks, "disturbance": disturbance, "pose_noise": pose_noise,
            "split": split,
            "perception": perception,
            "interface": interface,
            "task": task,
            "goal_observation": goal_observation,
            "slots": slots,
        }  # fmt: skip
        self.options = opts = EnvOptions(**kwargs)  # validates every option
        self.render_mode = render_mode
        self._goals = EpisodeGoals(opts.task)
        self.scenes = self._goals.usable(opts.scenes())  # those the task has a goal in
        self.options = opts = opts.fitted(self.scenes)  # objects interface: rows and slots
        self.universe: Universe = ground_universe(opts.universe_key())
        actions = spaces.Discrete(self.universe.n_actions)
        self._objects: ObjectInterface | None = None
        if opts.interface == "objects":  # fixed spaces over object slots (env.objects)
            self._objects = ObjectInterface(self.universe, slots=opts.slots or 0)
            actions = self._objects.action_space
        self.action_space, self._n_actions = actions, int(actions.n)
        self._state = SymbolicState(self.universe, opts.masks)
        self._grounding = make_grounding(opts, self.universe, self._state)
        self._observation = Observer(
            opts, self.universe, self._state, self._grounding, self._objects
        )
        self.observation_space = self._observation.space
        self._shaping = opts.reward_shaping
        self._task = KitchenTask(
            shaping=opts.reward_shaping, terminate_on_failure=opts.terminate_on_failure
        )
        self._initial_atoms = InitialAtoms(
            self.universe.domain, opts.domain, opts.affordances, opts.noise
        )
        self._episode: Episode | None = None  # set by reset
        self._last: tuple[MacroResult | None, tuple[str, ...]] = (None, ())
        self._rendering = Rendering(
            render_mode,
            self._render_frame,
            self._grounding.draw,
            self._grounding.simulator,
            "UTampKitchen",
        )
        self.metadata = {**type(self).metadata, "render_fps": self._rendering.fps}

    # ------------------------------------------------------------------ public helpers
    @property
    def goal(self) -> Goal:
        """The episode's goal (`utamp_gym.env.goals`: the option ``task``, default the
        scene's own goal, else the paper's tower)."""
        if self._episode is None:
            raise RuntimeError("call reset() before reading the goal")
        return self._episode.goal

    @property
    def instruction(self) -> str:
        """The episode's goal in words (``info["instruction"]``)."""
        if self._episode is None:
            raise RuntimeError("no episode yet: call reset() first")
        return self._episode.instruction

    def action_masks(self) -> np.ndarray:
        """Bool mask of the applicable actions (the sb3-contrib `MaskablePPO` convention)."""
        if self._objects is not None:
            return self._objects.mask(self._state.mask())
        return self._state.mask()

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Obs, dict[str, Any]]:
        super().reset(seed=seed)
        scene, world_seed = chosen_scene(self.scenes, options, self.np_random)
        self._episode = episode = Episode.start(scene, self._goals)
        atoms = self._initial_atoms(scene, self.np_random, self._goals.override(scene))
        self._state.reset(atoms, cache_key=None if self._initial_atoms.noisy else scene.key)
        self._grounding.reset(scene, atoms.static, self.np_random, world_seed)
        goal, progress = self._grounding.progress(
            episode.goal, episode.base, self.options.reward_shaping
        )
        self._task.initialize_episode(progress)
        self._rendering.reset()
        if self._objects is not None:  # drawn last: the other draws match the grounded env's
            self._objects.reset(scene, self.np_random)
        self._observation.reset(scene, atoms)
        return self._observation(), self._info(episode, goal, None, None, NOT_RUN, {})

    def step(self, action: Any) -> tuple[Obs, SupportsFloat, bool, bool, dict[str, Any]]:
        episode, state, grounding = self._episode, self._state, self._grounding
        if episode is None:
            action_id(action, self._n_actions)
            raise RuntimeError("call reset() before step()")
        if self._objects is None:
            a, failure = action_id(action, self.universe.n_actions), None
        else:
            a, failure = self._ground(action)
        stepped = NOT_RUN
        if a is None:  # an object-centric index without a ground action in this scene
            pass
        elif not state.allowed(a):  # the mask (with masks="affordances": applicable)
            failure = state.failure(a)
        else:  # the grounding runs it: the backend executes (or the outcome model decides)
            stepped = grounding.step(a, self.np_random)
            failure = stepped.failure
        goal, progress = grounding.progress(episode.goal, episode.base, self._shaping)
        reward, terminated = self._task.outcome(
            goal=goal, failed=failure is not None, progress=progress
        )
        perception = grounding.perception  # None (symbolic grounding): no anomalies
        anomalies = {} if perception is None else dict(perception.anomalies)
        terminated = terminated or state.dead_end() or bool(anomalies)
        info = self._info(episode, goal, a, failure, stepped, anomalies)
        self._rendering.step()
        return self._observation(), reward, terminated, False, info

    def render(self) -> np.ndarray | list[np.ndarray] | None:  # type: ignore[override]
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        return self._rendering.render()

    def close(self) -> None:
        self._rendering.close()
        self._grounding.close()

    # ------------------------------------------------------------------ internals
    def _ground(self, action: Any) -> tuple[int | None, str | None]:
        """(universe id, None) of an action; with the objects interface (None, why) for an
        index that has no ground action in this scene."""
        if self._objects is None:
            return action_id(action, self.universe.n_actions), None
        index = action_id(action, self._n_actions)
        a = self._objects.resolve(index, self._state.mask(), self._state.applicable_mask())
        if a is None:
            return None, f"no such action in scene {self.scene.name}: " + (
                self._objects.describe(index)
            )
        return a, None

    def _render_frame(self) -> np.ndarray:
        """What ``render()`` shows: the camera (physics) or the labelled schematic."""
        return self._grounding.frame(self.options.render_size)

    def _info(
        self,
        episode: Episode,
        goal: bool,
        a: int | None,
        failure: str | None,
        stepped: Stepped,
        anomalies: dict[str, str],
    ) -> dict[str, Any]:
        if stepped is NOT_RUN:  # every symbolic step that did not fail: nothing to report
            self._last = (None, ())
            macro, unexpected, fault = None, (), None
        else:
            macro, unexpected, fault = stepped.macro, stepped.unexpected, stepped.fault
            self._last = (macro, unexpected)
        return episode.info(
            StepRecord(
                action=None if a is None else self.universe.actions[a],
                mask=self.action_masks(),
                success=goal,
                failure=failure,
                timings=stepped.timings if self._grounding.recorded else None,
                macro=macro,
                unexpected=unexpected,
                anomalies=anomalies,
                fault=fault,
            )
        )

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict[str, Any]:
        """Pickle the universe by its key (re-grounded or taken from the cache on load)."""
        state = self.__dict__.copy()
        state["universe"] = self.universe.key
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """The backend rebuilt its simulation (`utamp_gym.sim.snapshot`); rendering watches it
        again."""
        state["universe"] = ground_universe(state["universe"])
        self.__dict__.update(state)
        self._rendering.attach()
