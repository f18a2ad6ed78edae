"""The symbolic state of one episode: the fluent atoms and the action mask.

Why: this is the env's fast path, and on small arrays numpy's per-call overhead, not the
arithmetic, dominates. So the state is a Python int (bit j = fluent atom j; effects are two
int operations) and the mask over *all* actions is a handful of numpy calls: the bits
``[s, 1 - s]`` as 64-bit words, each op's fluent literals as bits of the same words (an op
applies when none of its literals' bits is set), AND, OR over the words, compare with 0.
When those words outnumber the ops' literals (the procedural universe: 10 words x 3,770
ops against 31,000 literals), the bits are unpacked instead, every op's literals gathered
and `np.add.reduceat` counts the violated ones (on the kitchen universes that took a third
more than the words). There is no Python loop over actions per step. Ops whose static
precondition fails in the episode's scene (fixed at `reset`) are reduced to one
always-violated literal. Explaining a failure walks one op's precondition in Python, which
only happens on a failing step.

Mask modes (the env option ``masks``): ``"affordances"`` and ``"geometric"`` show the agent
the ops whose (universe) precondition holds; ``"none"`` shows every op whose objects are all
in the episode's scene (`Universe.action_objects`), fixed per episode. `applicable` is always
the precondition, whatever is shown: an op the mask allows may still not be applicable.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from utamp_gym.symbolic.atoms import EpisodeAtoms
from utamp_gym.symbolic.scene_cache import SceneCache
from utamp_gym.symbolic.universe import Universe, UniverseByKey

MASK_MODES = ("affordances", "geometric", "none")


_WORD = np.dtype("<u8")
#: every op's fluent literals: (n_words, n_ops) words, or (literal bits, row starts)
Checks = np.ndarray | tuple[np.ndarray, np.ndarray]


def _words(flat: np.ndarray, ptr: np.ndarray, n_words: int) -> np.ndarray:
    """(n_words, n_ops) words: bit b of word w of op i set when op i has a literal on the
    extended bit ``64 w + b`` (`flat`, rows starting at `ptr`, the last entry its end)."""
    lengths = np.diff(ptr)
    row = np.repeat(np.arange(len(lengths)), lengths)
    out = np.zeros((n_words, len(lengths)), _WORD)
    bits = np.left_shift(np.uint64(1), (flat % 64).astype(np.uint64))
    np.bitwise_or.at(out, (flat // 64, row), bits)
    return out


class SymbolicState(UniverseByKey):  # pickled with its universe by key
    """Fluent state over `universe.fluent_atoms`, the per-episode static filter and the mask."""

    def __init__(self, universe: Universe, masks: str = "affordances") -> None:
        if masks not in MASK_MODES:
            raise ValueError(f"unknown mask mode {masks!r}; valid: {', '.join(MASK_MODES)}")
        self.universe = universe
        self.masks = masks
        self._fluent_preds = universe.domain.fluent_predicates()
        half = universe.half
        self.bits = 0
        self._goal = 0  # bits that must be set
        self._goal_not = 0  # bits that must be clear (negated goal literals)
        #: goal literals on atoms outside the universe: (atom, must hold); they can only be
        #: perceived (`unrepresented`), never reached by an action of the universe
        self._goal_outside: tuple[tuple[str, bool], ...] = ()
        self._invert = (1 << half) - 1
        self._half, self._n_fluent = half, len(universe.fluent_atoms)  # read every step
        self._nbytes = 8 * -(-2 * half // 64)  # [s, 1 - s] in whole 64-bit words
        self._static: frozenset[str] = frozenset()
        self._data = bytes(self._nbytes)  # `_refresh`'s bytes of [s, 1 - s]
        n_words = self._nbytes // 8
        self._by_words = n_words * universe.n_actions <= len(universe.check_flat)
        self._literals = self._checks(universe.check_flat, universe.check_ptr)
        self._hits = np.empty((n_words, universe.n_actions) if self._by_words else 0, _WORD)
        self._mask = np.zeros(universe.n_actions, bool)
        self._tables: SceneCache[Checks] = SceneCache()
        self._present = np.zeros(universe.n_actions, bool)  # masks "none": objects in scene
        self._presence: SceneCache[np.ndarray] = SceneCache()
        self.unrepresented: tuple[str, ...] = ()  # perceived atoms outside the universe

    def reset(self, atoms: EpisodeAtoms, cache_key: str | None = None) -> None:
        """Start an episode: the scene's static atoms fix which ops can ever apply.

        The per-op literal table depends only on the static atoms, so it is cached under
        `cache_key` (the scene's `Scene.key` when those atoms are fixed per scene).
        """
        static = atoms.static
        if cache_key is None:
            self._literals = self._table(static)
        else:
            self._literals = self._tables.get(cache_key, lambda: self._table(static))
        self._static = static
        if self.masks == "none":
            if cache_key is None:
                self._present = self._objects_present(static)
            else:
                self._present = self._presence.get(cache_key, lambda: self._objects_present(static))
        self.unrepresented = ()
        self.bits = self.universe.state_bits(atoms.fluent)
        self.set_goal(atoms.goal, atoms.goal_negative)
        self._refresh()

    def observe(self, fluent: Iterable[str], static: frozenset[str]) -> None:
        """Set the state to perceived atoms (physics grounding, after every step).

        `static` replaces the episode's static atoms when it changed (a toppled object loses
        its orientation atoms); fluent atoms outside the universe cannot be represented and
        are left out (`unrepresented` lists them).
        """
        if static != self._static:
            self._literals = self._table(static)
            self._static = static
        index = self.universe.fluent_index
        bits, extra = 0, []
        for atom in fluent:
            j = index.get(atom)
            if j is None:
                extra.append(atom)
            else:
                bits |= 1 << j
        self.bits, self.unrepresented = bits, tuple(sorted(extra))
        self._refresh()

    def _table(self, static: frozenset[str]) -> Checks:
        """Every op's literals as words (`_words`): statically impossible ops get one literal
        on an always-1 bit (the inverted pad bit)."""
        u = self.universe
        ok = u.static_ok(u.pack_static(static))
        lengths = np.where(ok, np.diff(u.check_ptr), 1)
        ptr = np.zeros(len(lengths) + 1, np.int64)
        np.cumsum(lengths, out=ptr[1:])
        row = np.repeat(np.arange(len(lengths)), lengths)
        src = u.check_ptr[row] + (np.arange(ptr[-1]) - ptr[row])
        flat = np.where(ok[row], u.check_flat[src], u.half + len(u.fluent_atoms))
        return self._checks(flat, ptr)

    def _checks(self, flat: np.ndarray, ptr: np.ndarray) -> Checks:
        """The ops' literals (`flat`, rows starting at `ptr`, its last entry the end) as
        `_refresh` reads them: words (`_words`), or the literals and the row starts."""
        return _words(flat, ptr, self._nbytes // 8) if self._by_words else (flat, ptr[:-1])

    def _objects_present(self, static: frozenset[str]) -> np.ndarray:
        """Read-only bool array: the ops all of whose scene symbols are in the scene (every
        symbol of a scene has its ``isobjequal`` atom)."""
        here = {a[1:-1].split()[1] for a in static if a.startswith("(isobjequal ")}
        out = np.fromiter(
            (all(o in here for o in objs) for objs in self.universe.action_objects),
            bool,
            self.universe.n_actions,
        )
        out.setflags(write=False)
        return out

    def _refresh(self) -> None:
        x = self.bits | ((~self.bits & self._invert) << self._half)
        self._data = data = x.to_bytes(self._nbytes, "little")  # its first half is `bits`
        if isinstance(self._literals, np.ndarray):
            np.bitwise_and(self._literals, np.frombuffer(data, _WORD)[:, None], out=self._hits)
            self._mask = np.bitwise_or.reduce(self._hits, axis=0) == 0
        else:
            flat, starts = self._literals
            ext = np.unpackbits(np.frombuffer(data, np.uint8), bitorder="little").astype(np.intp)
            self._mask = np.add.reduceat(ext[flat], starts) == 0

    # ------------------------------------------------------------------ queries
    def mask(self) -> np.ndarray:
        """A fresh bool mask over all actions, what the agent is shown: the applicable ones
        (static and fluent preconditions hold), or with masks "none" those of the scene."""
        return (self._present if self.masks == "none" else self._mask).copy()

    def applicable_mask(self) -> np.ndarray:
        """Bool array over all actions: whose precondition holds now (read-only view; with
        masks other than "none" it is what `mask` shows)."""
        return self._mask

    def allowed(self, i: int) -> bool:
        """Whether the mask shows action `i`."""
        return bool((self._present if self.masks == "none" else self._mask)[i])

    def applicable(self, i: int) -> bool:
        """Whether action `i`'s precondition (of the universe's domain) holds now."""
        return bool(self._mask[i])

    def dead_end(self) -> bool:
        """No action is applicable (possible with noisy or rule-based affordances); with masks
        "none" too this looks at the preconditions, not at what the agent is shown."""
        m = self._mask
        return not (m.size and m[m.argmax()])  # argmax (the first True): 4x faster than any()

    def set_goal(self, positive: Iterable[str], negative: Iterable[str] = ()) -> None:
        """The atoms that must hold (`positive`) and must not (`negative`) at the goal."""
        index = self.universe.fluent_index
        yes, no = frozenset(positive), frozenset(negative)
        self._goal = self.universe.state_bits(a for a in yes if a in index)
        self._goal_not = self.universe.state_bits(a for a in no if a in index)
        self._goal_outside = tuple(sorted((a, a in yes) for a in yes | no if a not in index))

    def goal_reached(self) -> bool:
        """Every goal literal holds: its atom is true (negated literals: false)."""
        bits = self.bits
        if self._goal & ~bits or self._goal_not & bits:
            return False
        if self._goal_outside:
            seen = set(self.unrepresented)
            return all((a in seen) == positive for a, positive in self._goal_outside)
        return True

    def goal_literals_held(self) -> int:
        """How many goal literals hold now (reward shaping's progress, `utamp_gym.env.task`)."""
        bits = self.bits
        held = (self._goal & bits).bit_count() + (self._goal_not & ~bits).bit_count()
        if self._goal_outside:
            seen = set(self.unrepresented)
            held += sum((a in seen) == positive for a, positive in self._goal_outside)
        return held

    def vector(self) -> np.ndarray:
        """A fresh int8 0/1 vector over `universe.fluent_atoms`."""
        raw = np.frombuffer(self._data, np.uint8, self._half // 8)
        return np.unpackbits(raw, count=self._n_fluent, bitorder="little").view(np.int8)

    def true_atoms(self) -> list[str]:
        """The fluent atoms that hold, as lower-case PDDL (`unrepresented` ones last)."""
        return [*self.universe.atoms_of(self.bits), *self.unrepresented]

    @property
    def static_atoms(self) -> frozenset[str]:
        return self._static

    def failure(self, i: int) -> str | None:
        """Why action `i` is not applicable: its first false precondition, or None."""
        if self._mask[i]:
            return None
        u = self.universe
        fluent = self._fluent_preds
        for lit in u.preconditions(i):
            text = str(lit.atom)
            if lit.atom.predicate == "=":
                holds = lit.atom.args[0] == lit.atom.args[1]
            elif lit.atom.predicate in fluent:
                j = u.fluent_index.get(text)
                holds = j is not None and bool(self.bits >> j & 1)
            else:
                holds = text in self._static
            if holds != lit.positive:
                kind = "fluent" if lit.atom.predicate in fluent else "static"
                return f"precondition {u.domain.show(lit)} of {u.actions[i]} is false ({kind})"
        return f"{u.actions[i]} is not applicable"  # unreachable: some literal must fail

    # ------------------------------------------------------------------ change
    def apply(self, i: int) -> None:
        """Apply action `i`'s effects (delete, then add); the caller checked applicability."""
        self.bits = self.universe.successor(self.bits, i)
        self._refresh()
