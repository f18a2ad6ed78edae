"""What a reset derives from its scene, kept per scene for the scenes met most recently.

Resets are frequent and a scene's derived data (initial atoms, the static-literal table, the
object-centric map, initial poses) is a pure function of the scene, so each env part keeps it
per scene, under `Scene.key` (the name and a digest of the content: a scene built in code
never shares an entry with a packaged scene of the same name). The caches are bounded: an
env that meets ever new scenes (a scene file per episode, say) keeps the `SCENES_KEPT` it
used last instead of growing for as long as it runs. The bound holds every packaged suite
and procedural split whole (a test checks it), so an env on one of them derives each scene
once. A miss only recomputes: deriving draws no random numbers.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Generic, TypeVar

V = TypeVar("V")

SCENES_KEPT = 1024


class SceneCache(Generic[V]):
    """Values by scene key (`Scene.key`) for the `size` scenes used most recently (least
    recently used out)."""

    def __init__(self, size: int | None = None) -> None:
        size = SCENES_KEPT if size is None else size  # read when made: a test can lower it
        if size < 1:
            raise ValueError(f"a scene cache keeps at least one scene, got size={size!r}")
        self.size = size
        self._items: OrderedDict[str, V] = OrderedDict()

    def get(self, name: str, make: Callable[[], V]) -> V:
        """The value for the scene keyed `name`; on a miss, ``make()`` computes it and it is
        kept."""
        value = self._items.get(name)
        if value is None:
            value = self._items[name] = make()
            if len(self._items) > self.size:
                self._items.popitem(last=False)
        else:
            self._items.move_to_end(name)
        return value

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, name: object) -> bool:
        return name in self._items
