"""Nav2's obstacle-layer rules for turning observations into marked and cleared cells.

Marking: a point marks its cell occupied when it lies within ``obstacle_max_range_m`` of the sensor (and
beyond ``obstacle_min_range_m``) and between ``min_obstacle_height_m`` and ``max_obstacle_height_m`` above
the ground. Clearing: the cells along the ray from the sensor to each point are set free, up to
``raytrace_max_range_m`` (the point's own cell is not cleared; a ray longer than the range is cut there and
clears to its end). Points outside the height band neither mark nor clear (Nav2 filters them out of both
buffers). Paper 001 §3.3 keeps stereo obstacles that are at least 5 cm above the ground, not suspended above
the robot (so at most its diameter high) and within 10 m: :meth:`ObstacleLayerParams.for_robot`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from planner.errors import InvalidInput
from planner.robot import RobotProfile

PAPER_MIN_HEIGHT_M = 0.05
"""Paper 001 §3.3: obstacles lower than this are ground."""
PAPER_RANGE_M = 10.0
"""Paper 001 §3.3: obstacles farther than this are not used."""


@dataclass(frozen=True)
class ObstacleLayerParams:
    """Nav2 ``obstacle_layer`` parameters (metres). ``inf_is_valid``: a scan beam with no return clears up
    to its ``range_max`` (Nav2 default false; true here because exploration learns free space that way)."""

    obstacle_max_range_m: float = PAPER_RANGE_M
    obstacle_min_range_m: float = 0.0
    raytrace_max_range_m: float = PAPER_RANGE_M
    raytrace_min_range_m: float = 0.0
    min_obstacle_height_m: float = PAPER_MIN_HEIGHT_M
    max_obstacle_height_m: float = 2.0
    inf_is_valid: bool = True

    def __post_init__(self) -> None:
        for name in ("obstacle_max_range_m", "obstacle_min_range_m", "raytrace_max_range_m",
                     "raytrace_min_range_m", "min_obstacle_height_m", "max_obstacle_height_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
                raise InvalidInput(f"layer.{name}", f"must be a finite number, got {value!r}")
        if not 0 <= self.obstacle_min_range_m < self.obstacle_max_range_m:
            raise InvalidInput("layer.obstacle_max_range_m", "must be > obstacle_min_range_m ≥ 0")
        if not 0 <= self.raytrace_min_range_m < self.raytrace_max_range_m:
            raise InvalidInput("layer.raytrace_max_range_m", "must be > raytrace_min_range_m ≥ 0")
        if self.max_obstacle_height_m <= self.min_obstacle_height_m:
            raise InvalidInput("layer.max_obstacle_height_m", "must be > min_obstacle_height_m")

    @classmethod
    def for_robot(cls, robot: RobotProfile, range_m: float = PAPER_RANGE_M) -> ObstacleLayerParams:
        """Paper 001's filter for ``robot``: ≥ 5 cm above the ground, at most the sphere's diameter high,
        within ``range_m`` (10 m)."""
        return cls(obstacle_max_range_m=range_m, raytrace_max_range_m=range_m,
                   min_obstacle_height_m=PAPER_MIN_HEIGHT_M, max_obstacle_height_m=2.0 * robot.radius_m)
