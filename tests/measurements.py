"""A synthetic perceiver measurement row (what `perception.learned.measurements` returns),
shared by the tests of the learned attribute model and of its fitting."""

from __future__ import annotations

from utamp_gym.perception.learned import MATERIAL_NAMES, SHAPE_CLASSES
from utamp_gym.perception.material import FEATURES


def cylinder_measurements(
    size: float = 0.08, posterior: dict[str, float] | None = None
) -> dict[str, float | str]:
    """An upright open cylinder `size` across and 10 cm tall, every appearance feature 0 and
    the hand-built posterior uniform unless given (material -> probability)."""
    m: dict[str, float | str] = dict.fromkeys(FEATURES, 0.0)
    m.update({f"post_{n}": 1.0 / len(MATERIAL_NAMES) for n in MATERIAL_NAMES})
    m.update({f"post_{n}": p for n, p in (posterior or {}).items()})
    m.update({
        "shape_class": SHAPE_CLASSES[0], "top_shape": "open", "cylinder": 1.0, "size_0": size,
        "size_1": size, "size_2": 0.1, "height": 0.1, "top_rim": 0.0, "top_floor": 0.0,
        "top_visible": 1.0, "covered": 0.0, "flare": 0.0, "n_members": 1.0, "volume": 1e-4,
        "area": 0.02, "envelope": size * size * 0.1, "members_volume": 1e-4,
    })  # fmt: skip
    return m
