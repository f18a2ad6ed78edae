"""What the splits of procedural-v1 are: their families, sizes and instance pools, and the
generator's limits (reach, height, attempts)."""

from __future__ import annotations

from typing import NamedTuple

from utamp_gym.errors import UnknownNameError
from utamp_gym.scene.model import Scene

VERSION = "v1"
SUITE = f"procedural-{VERSION}"
SPLITS = ("train", "test-instances", "test-families", "test-count")
SPLIT_SUITES = tuple(f"{SUITE}/{s}" for s in SPLITS)
#: families of the objects on the base (bases are drawn from `BASES`)
TRAIN_FAMILIES = (
    "mug", "tumbler", "bowl", "plate", "food-box", "bottle",
    "frying-pan", "stock-pot", "paddle-board", "utensil",
)  # fmt: skip
HELD_OUT = ("jar", "container", "saucepan", "sheet-pan")
BASES = ("tray", "chopping-board")
HELD_OUT_BASES = ("sheet-pan",)
#: instance seeds: the training pool is [0, 2**31), the test pool [2**31, 2**32)
POOLS = ((0, 2**31), (2**31, 2**32))
BASE_NAME = "base"
OBJECT_NAMES = (BASE_NAME, "obj1", "obj2", "obj3", "obj4", "obj5")
JITTER = 0.03  # m, the base's shift from slot1's position (each axis)
REACH = 0.74  # m from the robot's base (horizontal) to any member's centre
#: m between the footprints of two stacks: room for the hand beside a low rim or body. At
#: 2 cm the wrist (link 7) met a tumbler 15 mm deep over a plate's rim (test-count/0065 of
#: the first draw), and a finger lifting one tumbler grazed the next
STACK_GAP = 0.06
MAX_TOTAL_HEIGHT = 0.42  # m, all objects stacked
ATTEMPTS = 40  # draws of instances, stacks and layouts before giving up
TOWERS = 20  # goal towers tried per seed
LEVEL_ATTEMPTS = 40  # draws of family and instance for one level of a goal tower
MIN_CARRY = 0.07  # m, the narrowest surface a goal tower goes on from (a mug fits)
FREE_SHARE = 0.25  # seeds whose objects are drawn without building a goal tower
UNACHIEVABLE_SHARE = 0.1
SIZES = {"train": 25 * 9, "test-instances": 12 * 9, "test-families": 12 * 9, "test-count": 12 * 9}
SEEDS_FILE = ("procedural", f"procedural-{VERSION}.toml")


class SplitSpec(NamedTuple):
    families: tuple[str, ...]
    bases: tuple[str, ...]
    sizes: tuple[int, ...]  # objects per scene, the base included
    pool: int  # index into POOLS
    new: tuple[str, ...] = ()  # at least one object of these families


SPECS = {
    "train": SplitSpec(TRAIN_FAMILIES, BASES, (2, 3, 4, 5), 0),
    "test-instances": SplitSpec(TRAIN_FAMILIES, BASES, (2, 3, 4, 5), 1),
    "test-families": SplitSpec(
        (*TRAIN_FAMILIES, *HELD_OUT[:3]),
        (*BASES, *HELD_OUT_BASES),
        (2, 3, 4, 5),
        1,
        new=HELD_OUT,
    ),
    "test-count": SplitSpec(TRAIN_FAMILIES, BASES, (6,), 0),
}


class Config(NamedTuple):
    """What a procedural suite version draws from: its name (scene names), the version in
    its generator's seed (`kitchenware.params.rng_for`), its splits and object names. The
    kitchenware instances are always the families' `VERSION` ones."""

    suite: str
    version: str
    specs: dict[str, SplitSpec]
    names: tuple[str, ...]
    free_share: float = FREE_SHARE
    max_height: float = MAX_TOTAL_HEIGHT  # m, all objects of a scene stacked


V1 = Config(SUITE, VERSION, SPECS, OBJECT_NAMES)


class Generated(NamedTuple):
    """One generated scene and what it was made of."""

    scene: Scene
    seed: int
    families: tuple[str, ...]  # per object, scene order (the base first)
    achievable: bool


class NoLayout(Exception):
    """No valid stacks and layout were found for a seed (it is skipped by `select_seeds`)."""


def _check_split(split: str) -> str:
    if split not in SPECS:
        raise UnknownNameError("procedural split", split, SPLITS)
    return split
