"""The goal part of the object-centric observation (env option ``goal_observation=True``).

Why: one policy for every goal needs the goal in the same terms as the state it sees. A goal
is a set of literals over the fluent atoms (`utamp_gym.tasks.goal`); every goal template
speaks of relations between object parts and supports (an object stands on a support, a
surface is clear), so the goal is written in the layout of the observation's own relation
entries, in the interface's slot order (`utamp_gym.env.objects`; E = `N_ENTITIES`: object
slots, then table regions, then free spaces):

* ``goal_contact`` (E, E, 7) and ``goal_free`` (E, 7): the literals that must hold, as
  ``contact`` and ``free`` would show them (``goal_contact[a, b, p]``: part p of entity a
  must touch entity b, so "slot 3 stands on region 1" is its standing part touching region 1;
  ``goal_free[a, p]``: nothing on part p of a, a clear surface);
* ``goal_not_contact`` (E, E, 7) and ``goal_not_free`` (E, 7): the negated literals ("X stands
  on none of these supports", the templates' "anywhere on the table" and "in any order").

The hand-empty literal every goal has is not encoded (``held`` shows the hand). With the
grounded interface the goal is ``goal`` / ``goal_not``: bits over the universe's fluent atoms
in ``symbolic``'s order (the atoms that must / must not hold). The entries
are fixed for an episode. An env id whose spaces include them is a new id
(``UTampKitchenGoals-v0``); the spaces of ``UTampKitchenProcedural-v0`` are unchanged.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from gymnasium import spaces

from utamp_gym.env.object_space import MAX_OBJECTS, n_entities
from utamp_gym.env.objects import ObjectInterface
from utamp_gym.scene.geometry import PARTS
from utamp_gym.symbolic.atoms import EpisodeAtoms
from utamp_gym.symbolic.universe import Universe

#: the goal's observation keys
GOAL_KEYS = ("goal_contact", "goal_free", "goal_not_contact", "goal_not_free")


def goal_spaces(k: int = MAX_OBJECTS) -> dict[str, spaces.Space]:
    """The goal entries' spaces (added to the objects interface's ``Dict``; `k` object
    slots)."""
    e, p = n_entities(k), len(PARTS)
    contact, free = spaces.MultiBinary((e, e, p)), spaces.MultiBinary((e, p))
    return dict(zip(GOAL_KEYS, (contact, free, contact, free), strict=True))


def goal_observation(
    interface: ObjectInterface, positive: frozenset[str], negative: frozenset[str]
) -> dict[str, np.ndarray]:
    """The goal entries of an episode whose slots `interface` has placed (after its reset):
    `positive` atoms must hold, `negative` must not."""
    yes, no = interface.fluent_layout(positive), interface.fluent_layout(negative)
    return {
        "goal_contact": yes["contact"],
        "goal_free": yes["free"],
        "goal_not_contact": no["contact"],
        "goal_not_free": no["free"],
    }


def symbolic_goal_spaces(n_fluents: int) -> dict[str, spaces.Space]:
    """The grounded interface's goal entries: ``goal`` / ``goal_not`` over the universe's
    fluent atoms (``symbolic``'s order): the atoms that must / must not hold."""
    return {"goal": spaces.MultiBinary(n_fluents), "goal_not": spaces.MultiBinary(n_fluents)}


def symbolic_goal_observation(
    fluent_index: Mapping[str, int], positive: frozenset[str], negative: frozenset[str]
) -> dict[str, np.ndarray]:
    """``goal`` / ``goal_not`` (atoms outside the universe are left out)."""
    out = {}
    for key, atoms in (("goal", positive), ("goal_not", negative)):
        v = np.zeros(len(fluent_index), np.int8)
        v[[fluent_index[a] for a in atoms if a in fluent_index]] = 1
        out[key] = v
    return out


def goal_entry_spaces(
    objects: ObjectInterface | None, universe: Universe
) -> dict[str, spaces.Space]:
    """The goal entries' spaces of an env with the objects interface `objects`, or (None)
    the grounded one over `universe`."""
    if objects is not None:
        return goal_spaces(objects.k)
    return symbolic_goal_spaces(len(universe.fluent_atoms))


def goal_entries(
    objects: ObjectInterface | None, universe: Universe, atoms: EpisodeAtoms
) -> dict[str, np.ndarray]:
    """The episode's goal entries (`objects` placed its slots already)."""
    if objects is not None:
        return goal_observation(objects, atoms.goal, atoms.goal_negative)
    return symbolic_goal_observation(universe.fluent_index, atoms.goal, atoms.goal_negative)


__all__ = [
    "GOAL_KEYS",
    "goal_entries",
    "goal_entry_spaces",
    "goal_observation",
    "goal_spaces",
    "symbolic_goal_observation",
    "symbolic_goal_spaces",
]
