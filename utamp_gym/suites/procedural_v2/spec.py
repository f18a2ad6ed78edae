"""What the splits of procedural-v2 are: the v1 generator's objects and layouts (`Config`
`V2`: up to 8 objects, its own seeds) with a goal of kitchen organisation per scene, drawn
from the split's templates (`TEMPLATES`).

Held out from ``train`` (documented here and in the split file): the templates ``sort`` and
``unstack`` (`HELD_OUT_TEMPLATES`) and the compositions ``clear+in-region`` and
``put-on+in-region`` of seen templates (`HELD_OUT_COMPOSITIONS`); ``test-tasks`` holds only
these. ``hard`` (`procedural-v2/hard`) keeps achievable scenes of 5-6 objects whose plan
takes at least `HARD_MIN_ACTIONS` actions, with the hard suite's own template ``restack``
(every object but the base in one stack in a given order that turns over a pair standing
one on another now, so the plan takes it apart with temporary placements) beside the tower,
two stacks and sort. (6-8 objects: about one seed in ten has a layout and fewer still a
goal of 12 actions; 5-6 objects give the same plan lengths at a few times the yield.)
"""

from __future__ import annotations

from utamp_gym.errors import UnknownNameError
from utamp_gym.suites.procedural.spec import (
    BASES,
    HELD_OUT,
    HELD_OUT_BASES,
    MAX_TOTAL_HEIGHT,
    TRAIN_FAMILIES,
    Config,
    SplitSpec,
)

VERSION = "v2"
SUITE = f"procedural-{VERSION}"
SPLITS = ("train", "test-instances", "test-families", "test-count", "test-tasks", "hard")
SPLIT_SUITES = tuple(f"{SUITE}/{s}" for s in SPLITS)
OBJECT_NAMES = ("base", *(f"obj{i}" for i in range(1, 8)))
#: the domain the achievability labels assume (kept in the split file): the extended one,
#: whose rim pinches lift bowls, plates and pans (issue 39)
DOMAIN = "utamp2x"
#: the planner method that labels each goal (Fast Downward's translator checks it)
LABEL_METHOD = "utamp2x-rules"
LABEL_TIMEOUT = 60.0  # s per scene and planner
TRAIN_TEMPLATES = (
    "tower", "subset-on", "two-stacks", "put-on", "clear", "in-region",
    "put-on+clear", "in-region+in-region",
)  # fmt: skip
HELD_OUT_TEMPLATES = ("sort", "unstack")
HELD_OUT_COMPOSITIONS = ("clear+in-region", "put-on+in-region")
HARD_TEMPLATES = ("restack", "tower", "two-stacks", "sort")
HARD_MIN_ACTIONS = 12
#: goal ids each split draws from (uniformly per seed)
SPLIT_TEMPLATES = {
    "train": TRAIN_TEMPLATES,
    "test-instances": TRAIN_TEMPLATES,
    "test-families": TRAIN_TEMPLATES,
    "test-count": TRAIN_TEMPLATES,
    "test-tasks": (*HELD_OUT_TEMPLATES, *HELD_OUT_COMPOSITIONS),
    "hard": HARD_TEMPLATES,
}
SIZES = {"train": 400, "test-instances": 100, "test-families": 100, "test-count": 100,
         "test-tasks": 100, "hard": 42}  # fmt: skip
#: the share of unachievable goals each split keeps (`HARD`: none)
UNACHIEVABLE_SHARE = 0.1
SPECS = {
    "train": SplitSpec(TRAIN_FAMILIES, BASES, (3, 4, 5), 0),
    "test-instances": SplitSpec(TRAIN_FAMILIES, BASES, (3, 4, 5), 1),
    "test-families": SplitSpec(
        (*TRAIN_FAMILIES, *HELD_OUT[:3]), (*BASES, *HELD_OUT_BASES), (3, 4, 5), 1, new=HELD_OUT
    ),
    "test-count": SplitSpec(TRAIN_FAMILIES, BASES, (6, 7, 8), 0),
    "test-tasks": SplitSpec(TRAIN_FAMILIES, BASES, (3, 4, 5), 1),
    "hard": SplitSpec(TRAIN_FAMILIES, BASES, (5, 6), 1),
}
#: a quarter of v1's seeds (half of v2's) draw their objects freely; the rest build a tower
#: of them within `MAX_HEIGHT` (v1: all objects within `MAX_GOAL_STACK`)
FREE_SHARE = 0.5
MAX_HEIGHT = 0.6  # m, all objects of a scene stacked
MAX_GOAL_STACK = MAX_TOTAL_HEIGHT  # m, the tallest stack a goal asks for (v1's scene limit)
V2 = Config(SUITE, VERSION, SPECS, OBJECT_NAMES, FREE_SHARE, MAX_HEIGHT)
GOAL_DRAWS = 6  # goals drawn per scene; the first that passes the quick checks is kept
RESTACK_DRAWS = 40  # restack's: few orders of a scene's objects can stand one on another
SEEDS_FILE = ("procedural", f"procedural-{VERSION}.toml")


def check_split(split: str) -> str:
    if split not in SPECS:
        raise UnknownNameError("procedural-v2 split", split, SPLITS)
    return split
