"""The attributes a method that detects them is scored on, one accuracy column each."""

#: per-attribute accuracy (fractions of objects, parts or members right; see
#: `utamp_gym.methods.perceived.attribute_accuracy`), stored as ``acc_<attribute>``
ATTRIBUTES = (
    "body",
    "members",
    "member_size",
    "shape",
    "surface",
    "height",
    "food",
    "material",
    "mass",
    "mass_class",
    "robustness",
)

__all__ = ["ATTRIBUTES"]
