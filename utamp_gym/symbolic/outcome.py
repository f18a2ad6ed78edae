"""The symbolic outcome model: in symbolic grounding, the world's stand-in for physics.

Why: with masks "geometric" or "none" the agent may choose actions that the world forbids
(a side grasp of the shaker, lifting the tray, a mug on the shaker's round top). Physics
grounding lets the simulator decide; symbolic grounding needs a model that decides the same
way without one. The model is the paper's: an action succeeds iff its ground-truth U-TAMP-2
precondition holds, i.e. its geometric precondition (the env's universe, checked on the
`SymbolicState`) and every affordance literal of the U-TAMP-2 action with the same arguments
(`canGraspFrom`, `canLift`, `not canLift`, `isSupportive`, `isSupportable`, `isP2PSupportive`,
`canSlide`) under the scene's ground truth (`ground_truth_for`, whatever the env's own
``affordances`` option says). A failed action changes nothing; its reason names the first
false literal, e.g. ``"canGraspFrom(salt, salt-body, left, front, back) is false (ground
truth)"``.

How: the affordance literals of every action of the universe are packed once per universe
into bit rows over the affordance atoms they mention (as `Universe.static_pre`), so a scene's
verdict for all actions is one vectorised check, done once per scene and cached.
`benchmarks/outcome_model.py` measures how often the model agrees with physics.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from utamp_gym.affordances.sources import ground_truth_for
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.atoms import parse_atom
from utamp_gym.symbolic.geometric import GEOMETRIC_DROPPED
from utamp_gym.symbolic.pddl import Domain, Literal, parse_domain
from utamp_gym.symbolic.problem import domain_text, instantiate_affordances
from utamp_gym.symbolic.scene_cache import SceneCache
from utamp_gym.symbolic.state import SymbolicState
from utamp_gym.symbolic.universe import Universe, UniverseKey, ground_universe

GROUND_TRUTH_DOMAIN = "utamp2"


@lru_cache(maxsize=1)
def _truth_domain() -> Domain:
    return parse_domain(domain_text(GROUND_TRUTH_DOMAIN), source="utamp2.pddl")


def affordance_literals(action: str) -> tuple[Literal, ...]:
    """The affordance literals of the U-TAMP-2 precondition of a ground action (PDDL text)."""
    name, *args = action.strip().strip("()").lower().split()
    pre = _truth_domain().actions[name].instantiate(args)[0]
    return tuple(lit for lit in pre if lit.atom.predicate in GEOMETRIC_DROPPED)


def show(lit: Literal) -> str:
    """``canGraspFrom(salt, salt-body, on, left, right)``, ``not canLift(tray, tray-body)``."""
    pred = _truth_domain().spelling.get(lit.atom.predicate, lit.atom.predicate)
    text = f"{pred}({', '.join(lit.atom.args)})"
    return text if lit.positive else f"not {text}"


@dataclass(frozen=True, eq=False)
class _TruthTable:
    """Per action, its affordance literals, and as rows of bits over `atoms` (read-only)."""

    literals: tuple[tuple[Literal, ...], ...]
    atoms: dict[str, int]
    pos: np.ndarray  # (n_actions, words) positive literals
    neg: np.ndarray  # (n_actions, words) negated literals


@lru_cache(maxsize=4)
def _truth_table(key: UniverseKey) -> _TruthTable:
    universe = ground_universe(key)
    lits = [affordance_literals(a) for a in universe.actions]
    atoms: dict[str, int] = {}
    for row in lits:
        for lit in row:
            atoms.setdefault(str(lit.atom), len(atoms))
    words = max(1, -(-len(atoms) // 64))
    pos = np.zeros((len(lits), words), np.uint64)
    neg = np.zeros((len(lits), words), np.uint64)
    for i, row in enumerate(lits):
        for lit in row:
            j = atoms[str(lit.atom)]
            out = pos if lit.positive else neg
            out[i, j >> 6] |= np.uint64(1) << np.uint64(j & 63)
    pos.setflags(write=False)
    neg.setflags(write=False)
    return _TruthTable(tuple(lits), atoms, pos, neg)


@lru_cache(maxsize=4)
def _shared_scenes(
    key: UniverseKey, domain: str = GROUND_TRUTH_DOMAIN
) -> SceneCache[tuple[frozenset[str], np.ndarray]]:
    """Per scene of one universe, its ground truth (`OutcomeModel.reset`), shared by every
    model of a process (a training vector's envs derive each scene once); read-only."""
    return SceneCache()


class OutcomeModel:
    """Decides a symbolic step by the ground-truth U-TAMP-2 precondition (module docstring)."""

    def __init__(self, universe: Universe, domain: str = GROUND_TRUTH_DOMAIN) -> None:
        """`domain`: whose ground truth decides (``utamp2x``: with the extended grasps; its
        actions are U-TAMP-2's)."""
        self.universe, self.domain = universe, domain
        self._table = _truth_table(universe.key)
        # scene name -> (ground-truth atoms, whether each action's affordances hold)
        self._scenes = _shared_scenes(universe.key, domain)
        self._ok = np.ones(universe.n_actions, bool)
        self._truth: frozenset[str] = frozenset()

    def __getstate__(self) -> dict[str, object]:
        """Pickle the universe (and its truth table) by key, as `SymbolicState` does."""
        state = self.__dict__.copy()
        state["universe"], state["_table"] = self.universe.key, None
        del state["_scenes"]  # the process's shared cache
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        key = state["universe"]
        assert isinstance(key, UniverseKey)
        state["universe"], state["_table"] = ground_universe(key), _truth_table(key)
        state["_scenes"] = _shared_scenes(key, state.get("domain", GROUND_TRUTH_DOMAIN))
        self.__dict__.update(state)

    def reset(self, scene: Scene) -> None:
        """Start an episode in `scene`: its ground-truth affordances decide from now on."""

        def derive() -> tuple[frozenset[str], np.ndarray]:
            truth, t = truth_atoms(scene, self.domain), self._table
            words = np.zeros(t.pos.shape[1], np.uint64)
            for a in truth:
                j = t.atoms.get(a)
                if j is not None:
                    words[j >> 6] |= np.uint64(1) << np.uint64(j & 63)
            ok = ~((t.pos & ~words) | (t.neg & words)).any(axis=1)
            ok.setflags(write=False)
            return truth, ok

        self._truth, self._ok = self._scenes.get(scene.key, derive)

    def affordances_hold(self) -> np.ndarray:
        """Read-only bool array: per action, whether its affordance literals hold here."""
        return self._ok

    def failure(self, state: SymbolicState, i: int) -> str | None:
        """Why action `i` fails in `state` (None: it succeeds): the first false precondition,
        geometric (the state's reason) or affordance (named, "... (ground truth)")."""
        if not state.applicable(i):
            return state.failure(i)
        return self.affordance_failure(i)

    def affordance_failure(self, i: int) -> str | None:
        """The first ground-truth affordance literal of action `i` that is false (None: all
        hold), as in `failure`, without looking at the geometric precondition."""
        if self._ok[i]:
            return None
        for lit in self._table.literals[i]:
            if (str(lit.atom) in self._truth) != lit.positive:
                return f"{show(lit)} is false (ground truth)"
        raise AssertionError(f"no false affordance literal for {self.universe.actions[i]}")


def truth_atoms(scene: Scene, domain: str = GROUND_TRUTH_DOMAIN) -> frozenset[str]:
    """The scene's ground-truth affordance atoms (of `domain`), lower-case PDDL."""
    facts = ground_truth_for(scene, domain)
    return frozenset(str(parse_atom(a)) for a in instantiate_affordances(scene, facts))
