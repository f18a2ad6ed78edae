"""`KitchenViews`: what a kitchen env's state looks like from outside, read-only.

Why a module of its own: `UTampKitchenEnv` (`utamp_gym.env.kitchen`) is the Gymnasium loop;
these properties only read what the loop keeps (the scene, the symbolic state, the last
step's physics), and are what planners, evaluations and tests query between steps.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from utamp_gym.env.object_space import action_texts
from utamp_gym.env.options import action_id
from utamp_gym.symbolic.atoms import parse_atom

if TYPE_CHECKING:
    from utamp_gym.backend import MacroResult, PhysicsBackend
    from utamp_gym.env.episode import Episode
    from utamp_gym.env.grounding import Grounding
    from utamp_gym.env.objects import ObjectInterface
    from utamp_gym.perception.abstraction import Perception
    from utamp_gym.scene.model import Scene
    from utamp_gym.symbolic.state import SymbolicState
    from utamp_gym.symbolic.universe import Universe


class KitchenViews:
    """Read-only views of a kitchen env (mixed into `UTampKitchenEnv`)."""

    universe: Universe
    _episode: Episode | None
    _state: SymbolicState
    _objects: ObjectInterface | None
    _grounding: Grounding
    _last: tuple[MacroResult | None, tuple[str, ...]]

    @property
    def scene(self) -> Scene:
        """The scene of the current episode."""
        if self._episode is None:
            raise RuntimeError("no episode yet: call reset() first")
        return self._episode.scene

    @property
    def action_strings(self) -> tuple[str, ...]:
        """What every action id means. Grounded interface: the PDDL string of each ground
        action (`universe` order). Objects interface: each index in the interface's own
        vocabulary, the same in every scene (``pick slot3 member0 grasp on/left/right``;
        `utamp_gym.env.object_space.action_text`); the PDDL action an index runs depends on
        the episode: `action_pddl`, and ``info["action"]`` after the step."""
        if self._objects is not None:
            return action_texts(self._objects.k)
        return self.universe.actions

    def action_pddl(self, action: int) -> str:
        """The PDDL string of the ground action that stepping `action` now would run (what
        ``info["action"]`` will say; grounded interface: ``action_strings[action]``). With the
        objects interface it depends on the scene, the slots and the state; ``""`` for an
        index without a ground action in this scene (its step fails: ``no such action``)."""
        if self._objects is None:
            return self.universe.actions[action_id(action, self.universe.n_actions)]
        index = action_id(action, self._objects.n_actions)
        if self._episode is None:
            raise RuntimeError("call reset() before action_pddl(): the slots are drawn there")
        a = self._objects.resolve(index, self._state.mask(), self._state.applicable_mask())
        return "" if a is None else self.universe.actions[a]

    @property
    def symbolic_atoms(self) -> tuple[str, ...]:
        """The fluent atom of every ``symbolic`` observation entry (predicates as declared)."""
        return tuple(self.universe.domain.show(parse_atom(a)) for a in self.universe.fluent_atoms)

    @property
    def static_atoms(self) -> frozenset[str]:
        """The current episode's static atoms (affordances, geometry), lower-case PDDL."""
        return self._state.static_atoms

    def true_atoms(self) -> list[str]:
        """The fluent atoms that hold now, lower-case PDDL."""
        return self._state.true_atoms()

    @property
    def objects(self) -> ObjectInterface | None:
        """The object-centric interface (``interface="objects"``; None otherwise)."""
        return self._objects

    @property
    def backend(self) -> PhysicsBackend:
        """The backend that grounds the env's actions, e.g. to read measured towers: the
        simulator (physics grounding) or the `SymbolicBackend` (symbolic grounding)."""
        return self._grounding.backend

    @property
    def macro_result(self) -> MacroResult | None:
        """The last step's `MacroResult` (None: no macro action reached the simulator)."""
        return self._last[0]

    @property
    def unexpected_atoms(self) -> list[str]:
        """The last step's unexpected atoms (``"+ATOM"`` / ``"-ATOM"``, sorted)."""
        return list(self._last[1])

    @property
    def anomalies(self) -> dict[str, str]:
        """The objects without a symbol now, with the reason (physics grounding)."""
        return self._anomalies()

    @property
    def perception(self) -> Perception | None:
        """The last perceived state (physics grounding; None in symbolic grounding)."""
        return self._grounding.perception

    def _anomalies(self) -> dict[str, str]:
        perception = self.perception
        return {} if perception is None else dict(perception.anomalies)
