"""The ``info`` dict of the kitchen envs: one fixed structure of numbers, bools and strings.

Why: datasets store infos step by step. Minari's `DataCollector(env, record_infos=True)`
stacks every info entry over an episode (a `jax.tree_util` map) and writes each stack to HDF5,
so every entry must keep its structure from `reset` to the last step, and every leaf must be a
number, a bool, a numpy array or a string: never None, never an object, never a dict or list
whose keys or length change. So:

======================  =================================================================
key                     value (after ``reset`` / when there is nothing to report)
======================  =================================================================
``action``              the action's PDDL string (``""``)
``action_mask``         bool array over the action space
``failure_reason``      why the action failed (``""``: it did not fail)
``timings``             float seconds per `TIMING_KEYS` in physics grounding with
                        ``record_timings=True`` (zeros where nothing ran); ``{}`` otherwise
``macro_result``        ``{"executed", "success", "reason", "retries"}``: whether a macro
                        action reached the simulator, its outcome, its reason, its retries
                        joined by ``"; "`` (not executed: ``False, False, "", ""``)
``unexpected_atoms``    ``"+ATOM"`` / ``"-ATOM"`` entries, sorted, joined by one space
                        (``""``); `split_atoms` gives the list back
``anomalies``           every object of the episode's scene -> why it has no symbol
                        (``""``: it has one)
``fault``               the injected fault (``""``)
``scene``               the scene's name
``is_success``          whether the goal holds now (as for the reward): True on the last
                        step of a solved episode, where SB3 and the RL Zoo read it
``goal``                the episode's goal literals, a tuple of PDDL strings (fixed for
                        the episode; `UTampKitchenEnv.goal` is the `Goal` itself)
``instruction``         the goal in words (`utamp_gym.env.goals`; fixed for the episode)
======================  =================================================================

Version history of this structure (the env ids stay v0: observations, actions and rewards are
unchanged): ``goal`` and ``instruction`` were added with scene goals (issue 38). Before that,
``action``, ``failure_reason`` and ``fault`` were None when empty, ``macro_result`` was the
`MacroResult` (or None), ``unexpected_atoms`` a list and ``anomalies`` held only the objects
without a symbol. The objects themselves are still there: `UTampKitchenEnv.macro_result`,
`UTampKitchenEnv.unexpected_atoms` and `UTampKitchenEnv.anomalies`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from utamp_gym.backend import MacroResult

#: the keys of ``info["timings"]`` in physics grounding with ``record_timings=True``: the
#: macro action's phases (`utamp_gym.sim.control.Timings`), perception and the whole step
TIMING_KEYS = ("ik_s", "plan_s", "sim_s", "wall_s", "sim_time_s", "perceive_s", "step_s")


def macro_info(macro: MacroResult | None) -> dict[str, Any]:
    """``info["macro_result"]``: a `MacroResult` as a fixed dict (not executed: None)."""
    if macro is None:
        return _NOT_EXECUTED.copy()
    return {
        "executed": True,
        "success": bool(macro.success),
        "reason": macro.reason or "",
        "retries": "; ".join(macro.retries),
    }


_NOT_EXECUTED = {"executed": False, "success": False, "reason": "", "retries": ""}


def timings_info(timings: Mapping[str, float] | None) -> dict[str, float]:
    """``info["timings"]`` when timings are recorded: every `TIMING_KEYS` entry (0 if absent)."""
    timings = timings or {}
    return {k: float(timings.get(k, 0.0)) for k in TIMING_KEYS}


def join_atoms(atoms: Iterable[str]) -> str:
    """``info["unexpected_atoms"]`` from its entries (``"+(oc ...)"``, ``"-(oc ...)"``)."""
    return " ".join(atoms)


def split_atoms(text: str) -> list[str]:
    """The entries of ``info["unexpected_atoms"]`` (each a sign and one parenthesised atom)."""
    return [f"{part})" if not part.endswith(")") else part for part in text.split(") ") if part]


def anomalies_info(objects: Iterable[str], anomalies: Mapping[str, str]) -> dict[str, str]:
    """``info["anomalies"]``: every object of the scene -> its anomaly (``""``: none)."""
    return {name: str(anomalies.get(name, "")) for name in objects}


@dataclass(slots=True, kw_only=True)
class StepRecord:
    """What one step (or reset) reports; `EpisodeInfo` puts it in the info's fixed structure.
    The defaults are a step that reports nothing: no action, no failure, no macro action.
    (Not frozen: a frozen dataclass takes about three times as long to make, every step.)"""

    mask: np.ndarray  # ``action_mask``
    success: bool  # ``is_success``: whether the goal holds now
    action: str | None = None  # the action's PDDL string
    failure: str | None = None  # why the action failed
    timings: Mapping[str, float] | None = None  # None: timings are not recorded
    macro: MacroResult | None = None  # None: no macro action reached the simulator
    unexpected: Iterable[str] = ()  # ``"+ATOM"`` / ``"-ATOM"`` entries, sorted
    anomalies: Mapping[str, str] | None = None  # the objects without a symbol -> why
    fault: str | None = None  # the injected fault


class EpisodeInfo:
    """The info dicts of one episode: the entries fixed for the episode (``scene``, ``goal``,
    ``instruction``, the all-empty ``anomalies``) are made once, at reset, and each step
    fills in the rest (every entry a fresh object: a caller may change what it is given)."""

    __slots__ = ("_calm", "goal", "instruction", "objects", "scene")

    def __init__(
        self, scene: str, objects: Iterable[str], goal: tuple[str, ...], instruction: str
    ) -> None:
        self.scene, self.objects = scene, tuple(objects)
        self.goal, self.instruction = goal, instruction
        self._calm = dict.fromkeys(self.objects, "")  # copied: copying beats building

    def __call__(self, step: StepRecord) -> dict[str, Any]:
        """One step's (or reset's) info in the fixed structure of the module docstring;
        ``step.timings`` None leaves ``info["timings"]`` empty (not recorded)."""
        timings, macro, anomalies = step.timings, step.macro, step.anomalies
        return {
            "action": step.action or "",
            "action_mask": step.mask,
            "failure_reason": step.failure or "",
            "timings": {} if timings is None else timings_info(timings),
            "macro_result": _NOT_EXECUTED.copy() if macro is None else macro_info(macro),
            "unexpected_atoms": join_atoms(step.unexpected) if step.unexpected else "",
            "anomalies": (
                anomalies_info(self.objects, anomalies) if anomalies else self._calm.copy()
            ),
            "fault": step.fault or "",
            "scene": self.scene,
            "is_success": bool(step.success),
            "goal": self.goal,
            "instruction": self.instruction,
        }
