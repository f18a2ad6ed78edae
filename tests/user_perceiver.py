"""A user's perceiver for tests/test_perceiver_protocol.py, loaded by name through the protocol.

It knows nothing of utamp_gym's internals beyond the protocol: it delegates the geometry to
the built-in perceiver and then reports its own reading of robustness, with a confidence
(and the alternatives it considered), as a user's model would.
"""

from __future__ import annotations

from utamp_gym.contract.perceiver import PerceivedAttributes, PerceptionRequest
from utamp_gym.methods.perceivers import BuiltinPerceiver


class CountingPerceiver:
    """The built-in reading, every robustness reported with confidence 0.9 (certain enough
    to plan with), counting its calls."""

    calls = 0

    def perceive(self, request: PerceptionRequest) -> dict[str, PerceivedAttributes]:
        type(self).calls += 1
        seen = BuiltinPerceiver().perceive(request)
        return {
            name: PerceivedAttributes(a.type, {"robustness": 0.9}, {"robustness": ("fragile",)})
            for name, a in seen.items()
        }


class BlindPerceiver:
    """Sees nothing: every run is lost at the perception stage."""

    def perceive(self, request: PerceptionRequest) -> dict[str, PerceivedAttributes]:
        return {}


class NotAPerceiver:
    """Has no perceive method."""
