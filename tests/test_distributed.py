"""The generic executor interface (what `utamp train --seeds K` will reuse): every task is
recorded once, as its result or as ``failed(task, reason)``."""

from __future__ import annotations

import pytest

from utamp_gym.distributed import LocalExecutor, make_executor


def _square_or_raise(x: int) -> int:  # module level: picklable for spawned workers
    if x == 3:
        raise ValueError("three")
    return x * x


@pytest.mark.parametrize("workers", [0, 2])
def test_local_executor_records_every_task_once(workers: int) -> None:
    got: list[object] = []
    LocalExecutor(workers).run(_square_or_raise, range(6), got.append, lambda t, r: (t, r))
    assert sorted(map(str, got)) == sorted(
        map(str, [0, 1, 4, (3, "crashed: ValueError: three"), 16, 25])
    )


def test_make_executor_local() -> None:
    assert make_executor("local", workers=3) == LocalExecutor(3)
