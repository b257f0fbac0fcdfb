"""The plan pipeline every door runs: a :class:`PlanQuery` built once at the door → a verified plan.

``sphereplan plan``, ``POST /v1/plan`` and the Zenoh ``sphereplan/plan`` queryable each read their request
into a :class:`PlanQuery` (the planner's own :class:`~planner.hybrid_astar.search.PlannerOptions`, parsed
once) and end in :func:`execute_plan`, so the same request gives the same plan whichever door it came
through. Kept free of pydantic and the web stack so that the CLI's cold start stays short.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from planner.hybrid_astar.plan import plan_path
from planner.hybrid_astar.search import PlannerOptions, Pose
from planner.occupancy import OccupancyGrid
from planner.result import PlanResult
from planner.robot import RobotProfile


@dataclass(frozen=True)
class PlanQuery:
    """One plan request: poses (x, y, yaw in the ``map`` frame), the planner's options and the request's
    own time limit (None: the options')."""

    start: Pose
    goal: Pose
    options: PlannerOptions
    time_limit_s: float | None = None

    @property
    def effective_time_limit_s(self) -> float:
        """The limit the plan runs under: the request's own, else the options'."""
        return float(self.options.time_limit_s if self.time_limit_s is None else self.time_limit_s)


def execute_plan(query: PlanQuery, grid: OccupancyGrid, robot: RobotProfile,
                 cancel: Callable[[], bool] | None = None) -> PlanResult:
    """Plan ``query`` on ``grid``.

    The time limit is passed to the planner per call rather than baked into the options, so that the
    cached planner (distance transform, heuristic grid) is reused across requests with different limits.
    ``cancel`` is polled between search chunks (:class:`~planner.errors.PlannerCancelled` when it says
    True). Raises the typed planning errors.
    """
    options = replace(query.options, time_limit_s=PlannerOptions.time_limit_s)
    return plan_path(grid, robot, query.start, query.goal, options, time_limit_s=query.effective_time_limit_s,
                     cancel=cancel)
