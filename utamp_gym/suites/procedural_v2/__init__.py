"""procedural-v2: procedural scenes with goals of kitchen organisation.

Objects and layouts come from v1's generator under its own seeds and limits (`spec.V2`; up to
8 objects in ``test-count`` and ``hard``); every scene carries a goal drawn from its split's
templates (`scenes`), labelled achievable or not by the planner and checked against Fast
Downward's translator (`labels`). The kept seeds and labels live in
``assets/procedural/procedural-v2.toml`` (`seeds`, written by `selection`). Splits
(`spec.SPLITS`): ``train``, ``test-instances``, ``test-families``, ``test-count``,
``test-tasks`` (held-out templates and compositions: `spec`) and ``hard``.
"""

from utamp_gym.suites.procedural_v2.scenes import GoalScene, generate_scene
from utamp_gym.suites.procedural_v2.seeds import (
    V2Scene,
    available_splits,
    parse_name,
    split_digest,
    split_domain,
    split_hash,
    split_names,
    split_scene,
    split_scenes,
    split_seeds,
)
from utamp_gym.suites.procedural_v2.spec import SPLIT_SUITES, SPLITS, SUITE

__all__ = [
    "SPLITS",
    "SPLIT_SUITES",
    "SUITE",
    "GoalScene",
    "V2Scene",
    "available_splits",
    "generate_scene",
    "parse_name",
    "split_digest",
    "split_domain",
    "split_hash",
    "split_names",
    "split_scene",
    "split_scenes",
    "split_seeds",
]
