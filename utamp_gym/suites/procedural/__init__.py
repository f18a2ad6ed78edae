"""Procedural scenes of generated kitchenware and the versioned splits of `procedural-v1`.

A scene is a pure function of (split, scene seed): its objects (a base and 1-5 others, each
an instance of a kitchenware family, `utamp_gym.kitchenware`), their orientations, initial
stacks and table layout are drawn from one generator seeded by a SHA-256 of the split and the
seed. The goal is the paper's: everything in one tower on the scene's base (``goal_base =
"base"``). A split is a fixed list of scene seeds kept in ``assets/procedural/procedural-v1.toml``
with the SHA-256 of its scene files (`~seeds.split_digest`, and of every 20th scene for
quick checks); scene ``procedural-v1/<split>/NNNN`` is
the NNNN-th seed of the list. The lists were chosen by `~selection.select_seeds` (run
``python -m utamp_gym.suites.procedural select``): the first seeds whose goal the rules call
achievable, plus a share (`~spec.UNACHIEVABLE_SHARE`) of seeds whose goal they call unachievable,
which planners must report unsolvable.

Splits (`~spec.SPLITS`):

* ``train``: 2-5 objects of the training families (`~spec.TRAIN_FAMILIES`), instances drawn
  from the training pool of instance seeds;
* ``test-instances``: the same families and counts, new instances (the test pool);
* ``test-families``: at least one object of a family never in train (`~spec.HELD_OUT`), new
  instances;
* ``test-count``: 6 objects (more than any train scene) of the training families.

Layouts: the base stands in slot1 of the suites' table (`assets/scenes/layout.toml`), every
other stack in its own slot 2-5, shifted by up to `~spec.JITTER` from the slot's position;
every object lies inside its slot, the workspace and `~spec.REACH` of the robot's base, and
stacks stand at least `~spec.STACK_GAP` apart (room for the hand beside one), and
the heights of all objects add up to at most `~spec.MAX_TOTAL_HEIGHT` (a tower of them leaves
the hand room under the workspace's ceiling).

The package, by responsibility: `spec` (what the splits are: families, sizes, pools, the
generator's limits), `objects` (which objects a scene holds, and whether its goal is
achievable), `layout` (initial stacks, table positions, the assembled scene:
`~layout.generate_scene`), `seeds` (the kept seed lists, their scenes, cache files, names and
digests), `selection` (choosing the seeds; ``python -m utamp_gym.suites.procedural``).
"""

from utamp_gym.suites.procedural.layout import (
    generate_scene,
)
from utamp_gym.suites.procedural.objects import (
    goal_achievable,
)
from utamp_gym.suites.procedural.seeds import (
    SAMPLE_STEP,
    parse_name,
    sample_hash,
    split_digest,
    split_hash,
    split_names,
    split_scene,
    split_scenes,
    split_seeds,
)
from utamp_gym.suites.procedural.seeds import (
    _seed_table as _seed_table,  # read by tests/test_procedural.py
)
from utamp_gym.suites.procedural.selection import (
    main,
    select_seeds,
)
from utamp_gym.suites.procedural.spec import (
    ATTEMPTS,
    BASE_NAME,
    BASES,
    FREE_SHARE,
    HELD_OUT,
    HELD_OUT_BASES,
    JITTER,
    LEVEL_ATTEMPTS,
    MAX_TOTAL_HEIGHT,
    MIN_CARRY,
    OBJECT_NAMES,
    POOLS,
    REACH,
    SEEDS_FILE,
    SIZES,
    SPECS,
    SPLIT_SUITES,
    SPLITS,
    STACK_GAP,
    SUITE,
    TOWERS,
    TRAIN_FAMILIES,
    UNACHIEVABLE_SHARE,
    VERSION,
    Generated,
    NoLayout,
    SplitSpec,
)

__all__ = [
    "ATTEMPTS",
    "BASES",
    "BASE_NAME",
    "FREE_SHARE",
    "HELD_OUT",
    "HELD_OUT_BASES",
    "JITTER",
    "LEVEL_ATTEMPTS",
    "MAX_TOTAL_HEIGHT",
    "MIN_CARRY",
    "OBJECT_NAMES",
    "POOLS",
    "REACH",
    "SAMPLE_STEP",
    "SEEDS_FILE",
    "SIZES",
    "SPECS",
    "SPLITS",
    "SPLIT_SUITES",
    "STACK_GAP",
    "SUITE",
    "TOWERS",
    "TRAIN_FAMILIES",
    "UNACHIEVABLE_SHARE",
    "VERSION",
    "Generated",
    "NoLayout",
    "SplitSpec",
    "generate_scene",
    "goal_achievable",
    "main",
    "parse_name",
    "sample_hash",
    "select_seeds",
    "split_digest",
    "split_hash",
    "split_names",
    "split_scene",
    "split_scenes",
    "split_seeds",
]
