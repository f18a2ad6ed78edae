"""Where a scene's affordance facts come from: the sources of the env and the planning methods.

* ``gt`` – the hand-written ground truth (`ground_truth_for`; types it does not cover get
  the rules' facts);
* ``rules`` – parsed from the types' true attributes (`utamp_gym.affordances.rules`);
* ``noisy`` – parsed from noisily detected attributes (`utamp_gym.affordances.noisy`, the
  offline stand-in for the paper's VLM detector), drawn with `detection_rng`;
* ``perceived`` (a method's source only) – the rules on a planning scene whose types were
  perceived in rendered views (``mug-seen``: `utamp_gym.methods.perceived`).

`affordances_for` returns the facts and their scores against the ground truth. Used by the
planning methods (`utamp_gym.planning.methods`) and the symbolic world model
(`utamp_gym.symbolic.atoms`); moved here from ``planning.methods``, which still exposes the
names.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

from utamp_gym.affordances.facts import Fact, Scores, packaged_ground_truth, restrict, score
from utamp_gym.errors import UnknownNameError
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.model import Scene

if TYPE_CHECKING:  # numpy, the rule parser and the noisy detector load only when used
    import numpy as np

#: where an env's affordances come from (env option ``affordances``)
AFFORDANCE_SOURCES = ("gt", "rules", "noisy")
#: ... and a method's: ``perceived`` are the rules on a planning scene's perceived types
METHOD_SOURCES = (*AFFORDANCE_SOURCES, "perceived")
#: suffix of the perceived types of a planning scene (``mug-seen``)
SEEN_SUFFIX = "-seen"
#: the noisy detector's default noise level (env option ``noise``)
DEFAULT_NOISE = 0.01


#: domains whose affordances include the extended grasps (`utamp_gym.affordances.rim`): the
#: rules derive them for these only, so the paper's domains plan as before
EXTENDED_DOMAINS = frozenset({"utamp2x"})


def scene_types(scene: Scene) -> list[ObjectType]:
    """The object types in a scene, the table's included."""
    names = dict.fromkeys([scene.table_type, *(o.type for o in scene.objects)])
    return [scene.catalogue[n] for n in names]


@lru_cache(maxsize=1)
def _packaged_ground_truth() -> tuple[frozenset[Fact], frozenset[str]]:
    """The packaged ground truth and the types it covers (computed once: a planner needs
    them on every call)."""
    truth = packaged_ground_truth()
    known = {n for f in truth for n in (f[1:2] if f[0] != "isP2PSupportive" else (f[2], f[4]))}
    return truth, frozenset(known)


def ground_truth_for(scene: Scene, domain: str = "utamp2") -> frozenset[Fact]:
    """Ground truth for the scene's types; types without hand-written truth use the rules
    (with the extended grasps for an extended `domain`, `EXTENDED_DOMAINS`)."""
    types = scene_types(scene)
    names = [t.name for t in types]
    truth, known = _packaged_ground_truth()
    gt = restrict(truth, names)
    unknown = {t.name for t in types} - known
    if not unknown:
        return gt
    derived = _rules(types, domain in EXTENDED_DOMAINS)
    extra = {f for f in derived if any(x in unknown for x in f[1:])}
    return gt | frozenset(extra)


def _rules(types: list[ObjectType], extended: bool = False) -> frozenset[Fact]:
    """The rules' facts on `types`. The rule parser loads only when used (`utamp plan` on
    types the ground truth covers never needs it: 9 ms of its start-up)."""
    # lazy: keeps `utamp plan` from loading utamp_gym.affordances.rules
    from utamp_gym.affordances.rules import derive_affordances

    return derive_affordances(types, extended)


def detection_rng(seed: int, scene_name: str) -> np.random.Generator:
    """The generator of a scene's noisy detection: independent per (seed, scene).

    Keyed on the scene name as well as the seed, so one seed of a sweep corrupts each
    scene differently (a per-seed stream would repeat one corruption in every scene).
    """
    import numpy as np

    # lazy: keeps `utamp --help` from loading utamp_gym.seeding
    from utamp_gym.seeding import scene_seed_sequence  # numpy: not on `utamp plan`'s path

    return np.random.default_rng(scene_seed_sequence(scene_name, seed))


def affordances_for(
    scene: Scene,
    source: str,
    rng: np.random.Generator | None,
    noise: float = DEFAULT_NOISE,
    domain: str = "utamp2",
) -> tuple[frozenset[Fact], Scores]:
    """Affordance facts of `source` for the scene, with their scores against the ground truth.

    `rng` drives the noisy detection (required for ``noisy``, unused otherwise). Source
    ``perceived`` needs a planning scene of perceived types (`utamp_gym.methods.perceived`);
    its scores here are against the rules on those types (1.0): the declared scene's
    ground truth is scored by `PerceivedScene.scores`."""
    if source not in METHOD_SOURCES:
        raise UnknownNameError("affordance source", source, METHOD_SOURCES)
    if source == "perceived":
        unseen = [o.name for o in scene.objects if not o.type.endswith(SEEN_SUFFIX)]
        if unseen:
            raise ValueError(
                f"utamp2-perceived plans a perceived scene, but the types of {', '.join(unseen)} "
                f"in '{scene.name}' are declared ones: perceive it first "
                "(utamp_gym.methods.perceived.perceive_scene or plan_perceived)"
            )
        facts = _rules(scene_types(scene))
        return facts, score(facts, facts)
    gt = ground_truth_for(scene, domain)
    if source == "gt":
        return gt, score(gt, gt)
    if source == "rules":
        facts = _rules(scene_types(scene), domain in EXTENDED_DOMAINS)
        return facts, score(facts, gt)
    if rng is None:
        raise ValueError("noisy affordance detection needs a random generator (rng)")
    # lazy: keeps `utamp --help` from loading utamp_gym.affordances.noisy
    from utamp_gym.affordances.noisy import detect_affordances

    det = detect_affordances(scene_types(scene), noise, rng, gt)
    return det.facts, det.scores


def plan_affordances(planning: Scene) -> frozenset[Fact]:
    """The ``perceived`` source's facts of a planning scene (the rules on its types)."""
    return affordances_for(planning, "perceived", None)[0]


__all__ = [
    "AFFORDANCE_SOURCES",
    "DEFAULT_NOISE",
    "EXTENDED_DOMAINS",
    "METHOD_SOURCES",
    "SEEN_SUFFIX",
    "affordances_for",
    "detection_rng",
    "ground_truth_for",
    "plan_affordances",
    "scene_types",
]
