"""Errors raised by sphereplan's algorithms.

Every failure is typed and says what was wrong and, for bad input, which field::

    SpherePlanError                     root of everything raised on purpose
    ├── InvalidInput(field, msg)        the caller sent something unusable      (CLI exit 2, HTTP 400/422)
    │   ├── MapError                    a map file or its image cannot be read
    │   └── RobotProfileError           a robot profile is malformed
    ├── NotFound(field, msg)            a named map/robot does not exist         (HTTP 404)
    └── PlanningError(code, msg)        planning ran but produced no path        (CLI exit 3/4)
        ├── BadEndpoint                 the start or goal is unusable            (CLI exit 2)
        │   ├── StartOutsideMap 203     ├── GoalOutsideMap 204
        │   └── StartOccupied   205     └── GoalOccupied   206
        ├── PlannerTimedOut   207       ├── NoValidPathFound 208
        └── PlannerCancelled  200

The numeric codes are Nav2's ``ComputePathToPose`` error codes (docs/contracts.md).
"""

from __future__ import annotations


class SpherePlanError(Exception):
    """Root of every error sphereplan raises on purpose."""


class InvalidInput(SpherePlanError, ValueError):
    """The caller sent something unusable; ``field`` names it."""

    def __init__(self, field: str, msg: str) -> None:
        super().__init__(f"{field}: {msg}")
        self.field = field
        self.msg = msg


class MapError(InvalidInput):
    """A map file, its YAML or its image cannot be used."""


class RobotProfileError(InvalidInput):
    """A robot profile is missing a field or has a bad value."""


class NotFound(SpherePlanError, LookupError):
    """A named resource (map, robot, problem) does not exist."""

    def __init__(self, field: str, msg: str) -> None:
        super().__init__(f"{field}: {msg}")
        self.field = field
        self.msg = msg


class PlanningError(SpherePlanError):
    """Planning ran but did not produce a path. ``code`` is the Nav2 error code."""

    code = 200

    def __init__(self, msg: str, *, planning_time_s: float = 0.0, expansions: int = 0) -> None:
        super().__init__(msg)
        self.msg = msg
        self.planning_time_s = planning_time_s
        self.expansions = expansions


class BadEndpoint(PlanningError):
    """The start or the goal is outside the map or occupied: the caller's input cannot be planned from."""


class StartOutsideMap(BadEndpoint):
    code = 203


class GoalOutsideMap(BadEndpoint):
    code = 204


class StartOccupied(BadEndpoint):
    code = 205


class GoalOccupied(BadEndpoint):
    code = 206


class PlannerTimedOut(PlanningError):
    code = 207


class NoValidPathFound(PlanningError):
    code = 208


class PlannerCancelled(PlanningError):
    code = 200
