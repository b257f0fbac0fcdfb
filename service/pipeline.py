"""The plan pipeline every door runs: request JSON → planner options, poses → a verified plan.

``sphereplan plan``, ``POST /v1/plan`` and the Zenoh ``sphereplan/plan`` queryable all end here, so the
same request gives the same plan whichever door it came through. Kept free of pydantic and the web
stack so that the CLI's cold start stays short.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from planner.hybrid_astar.plan import plan_path
from planner.hybrid_astar.search import PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.result import PlanResult
from planner.robot import RobotProfile


def pose_of(data: dict[str, Any]) -> tuple[float, float, float]:
    """(x, y, yaw) of a request pose object {x, y, yaw}."""
    return float(data["x"]), float(data["y"]), float(data["yaw"])


def execute_plan(request: dict[str, Any], grid: OccupancyGrid, robot: RobotProfile) -> PlanResult:
    """Plan the request (its ``start``, ``goal``, optional ``options`` and ``time_limit_s``) on ``grid``.

    The time limit is passed to the planner per call rather than baked into the options, so that the
    cached planner (distance transform, heuristic grid) is reused across requests with different limits.
    Raises :class:`~planner.errors.InvalidInput` for bad options and the typed planning errors.
    """
    options = PlannerOptions.from_dict(request.get("options") or {})
    time_limit = request.get("time_limit_s")
    if time_limit is None:
        time_limit = options.time_limit_s
    options = replace(options, time_limit_s=PlannerOptions.time_limit_s)
    return plan_path(grid, robot, pose_of(request["start"]), pose_of(request["goal"]), options,
                     time_limit_s=float(time_limit))
