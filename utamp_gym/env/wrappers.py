"""`SymbolicActionWrapper`: act on a kitchen env with PDDL action strings instead of ids.

Why: planners, plan files and people speak ``(pick-support mug mug-handle ...)``; agents
speak `Discrete` ids. The wrapper maps one to the other through the env's action universe, so a
plan produced outside the env can be replayed step by step.
"""

from __future__ import annotations

import string
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from utamp_gym.env.kitchen import Obs, UTampKitchenEnv

CHARSET = frozenset(string.ascii_letters + string.digits + "-_() ")


class SymbolicActionWrapper(gym.ActionWrapper[Obs, str, np.int64]):
    """Takes ground actions as PDDL strings, e.g. ``"(pick-support salt salt-body ...)"``.

    Matching ignores case, surrounding whitespace and repeated spaces. A string that is not
    one parenthesised action raises `ValueError`; a well-formed action outside the env's
    action space raises `UnknownNameError` (a `KeyError` listing valid actions). An action
    in the space whose preconditions fail is passed on: the env reports ``failure_reason``.
    The `action_space` is a `Text` space (sampling it yields random, unknown strings).
    """

    def __init__(self, env: gym.Env[Obs, Any]) -> None:
        super().__init__(env)
        kitchen = env.unwrapped
        if not isinstance(kitchen, UTampKitchenEnv):
            raise ValueError(f"SymbolicActionWrapper needs a UTampKitchenEnv, got {kitchen!r}")
        self._universe = kitchen.universe
        longest = max(len(a) for a in self._universe.actions)
        self.action_space = spaces.Text(max_length=2 * longest, charset=CHARSET)

    def action(self, action: str) -> int:
        """The env's id of a PDDL action string."""
        if not isinstance(action, str):
            raise ValueError(f"expected a PDDL action string such as '(pick-support ...)', got "
                             f"{action!r}")  # fmt: skip
        text = action.strip()
        inner = text[1:-1]
        if (
            not (text.startswith("(") and text.endswith(")"))
            or not inner.split()
            or any(c in inner for c in "()")
        ):
            raise ValueError(f"malformed action {action!r}: expected '(name arg ...)'")
        return self._universe.index(text)

    def action_string(self, action_id: int) -> str:
        """The PDDL string of an env action id."""
        return self._universe.actions[int(action_id)]
