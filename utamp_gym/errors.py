"""One exception hierarchy for utamp_gym.

Every message names what went wrong and, where there is a finite set of valid
choices, lists them, so a user can fix the input without reading the source.
"""

from __future__ import annotations

from collections.abc import Iterable


class UtampError(Exception):
    """Base class of every error raised by utamp_gym."""


class AssetError(UtampError, OSError):
    """A packaged asset (PDDL domain, catalogue, env definition) is missing."""


class SceneError(UtampError, ValueError):
    """A scene or catalogue file is malformed; the message names the file and the field."""

    def __init__(self, message: str, *, file: str | None = None, field: str | None = None):
        self.file = file
        self.field = field
        where = []
        if file:
            where.append(str(file))
        if field:
            where.append(f"field '{field}'")
        prefix = f"{': '.join(where)}: " if where else ""
        super().__init__(prefix + message)


class UnknownNameError(UtampError, KeyError):
    """A name (object, scene, method, env option, ...) that is not one of the valid choices."""

    def __init__(self, kind: str, name: str, valid: Iterable[str]):
        self.kind = kind
        self.name = name
        self.valid = sorted(valid)
        shown = ", ".join(self.valid[:40]) + (" ..." if len(self.valid) > 40 else "")
        super().__init__(f"unknown {kind} '{name}'; valid: {shown}")

    def __str__(self) -> str:  # KeyError would otherwise quote the message
        return self.args[0]


class PddlError(UtampError, ValueError):
    """A PDDL domain, problem or plan could not be parsed or grounded."""


class PlanningError(UtampError):
    """The planner failed for a reason other than proving the task unsolvable."""


class PlanningTimeout(PlanningError):
    """The planner exceeded its time limit; any planner process was killed.

    `phase` names the step that ran out of time (``grounding``, ``sas``, ``search``, ...).
    """

    def __init__(self, message: str, *, phase: str = "search"):
        self.phase = phase
        super().__init__(message)


class GroundingError(UtampError):
    """A symbolic action could not be turned into robot motion (IK, OMPL, decoding)."""


class SimulationError(UtampError):
    """The physics model could not be built or stepped."""


class EndpointError(UtampError):
    """A VLM endpoint is not configured, unreachable, or returned an unusable answer."""
