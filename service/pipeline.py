"""The plan pipeline every door runs: a :class:`PlanQuery` built once at the door → a verified plan.

``sphereplan plan``, ``POST /v1/plan`` and the Zenoh ``sphereplan/plan`` queryable each read their request
into a :class:`PlanQuery` (the planner's own :class:`~planner.hybrid_astar.search.PlannerOptions`, parsed
once) and end in :func:`execute_plan`, so the same request gives the same plan whichever door it came
through. Kept free of pydantic and the web stack so that the CLI's cold start stays short.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

from planner.errors import GoalOutsideMap, InvalidInput, PlannerTimedOut, StartOutsideMap
from planner.hybrid_astar.plan import plan_path, planner_for
from planner.hybrid_astar.search import PlannerOptions, Pose, rs_table_for, warm_up
from planner.maps.reachability import prepare as prepare_reachability
from planner.occupancy import OccupancyGrid
from planner.result import PlanResult
from planner.robot import RobotProfile
from planner.termination import Termination


@dataclass(frozen=True)
class PlanQuery:
    """One plan request: poses (x, y, yaw in the ``map`` frame), the planner's options and when to stop
    (the request's time limit; the worker attaches its cancel flag to the same object)."""

    start: Pose
    goal: Pose
    options: PlannerOptions
    termination: Termination = field(default_factory=Termination)


DEFAULT_OPTIONS = PlannerOptions()

#: most states a plan result may hold (~100 bytes of JSON each: a 20 MB reply)
MAX_RESULT_STATES = 200_000
#: a plan is assumed at most this many map diagonals (plus the start–goal distance) long when bounding its states
MAX_DETOUR_DIAGONALS = 4


def check_on_map(query: PlanQuery, grid: OccupancyGrid) -> None:
    """Raise Start/GoalOutsideMap for a pose off the grid, in floating point (a pose like 1e308 would
    overflow the planner's cell arithmetic)."""
    height, width = grid.data.shape
    x0, y0 = grid.origin[0], grid.origin[1]
    for pose, which, error in ((query.start, "start", StartOutsideMap), (query.goal, "goal", GoalOutsideMap)):
        x, y = pose[0], pose[1]
        if not (x0 <= x < x0 + width * grid.resolution_m and y0 <= y < y0 + height * grid.resolution_m):
            raise error(f"{which} ({x:.6g}, {y:.6g}) is outside the map {grid.name!r}")


def check_result_size(query: PlanQuery, grid: OccupancyGrid) -> None:
    """Refuse, before planning, a plan whose result could hold more than ``MAX_RESULT_STATES`` states.

    The result holds one state every ``options.state_spacing_m`` along the path; the path is taken to be at
    most the start–goal distance plus ``MAX_DETOUR_DIAGONALS`` diagonals of the map long.
    """
    height, width = grid.data.shape
    diagonal = math.hypot(width, height) * grid.resolution_m
    distance = math.dist(query.start[:2], query.goal[:2])
    spacing = query.options.state_spacing_m
    states = (distance + MAX_DETOUR_DIAGONALS * diagonal) / spacing
    if states > MAX_RESULT_STATES:
        least = (distance + MAX_DETOUR_DIAGONALS * diagonal) / MAX_RESULT_STATES
        raise InvalidInput("options.state_spacing_m", f"{spacing:g} m could return up to {states:.3g} states on "
                                                      f"this map; at most {MAX_RESULT_STATES} are returned "
                                                      f"(use ≥ {least:.3g} m)")


def execute_plan(query: PlanQuery, grid: OccupancyGrid, robot: RobotProfile) -> PlanResult:
    """Plan ``query`` on ``grid``; ``query.termination`` goes unchanged to the search loop (the options hold no
    time limit, so the cached planner — distance transform, heuristic grid — serves every limit). Raises the
    typed planning errors."""
    check_on_map(query, grid)
    check_result_size(query, grid)
    warm_up()  # one-off compilation happens before the clock
    options = query.options
    reverse = robot.reversible if options.allow_reverse is None else options.allow_reverse
    if reverse and options.n_yaw_bins == DEFAULT_OPTIONS.n_yaw_bins and not options.weighted_rs_heuristic:
        # one-off per built-in robot, like compilation (cached per process): before the clock
        rs_table_for(robot, options)
    clock = query.termination.start()
    if reverse:
        # request-sized precomputation is inside the limit and stops at it: the Reeds–Shepp table for the
        # request's own options.n_yaw_bins (≈ 6 s at 720 bins, and a table per weights with
        # options.weighted_rs_heuristic; cached per process once built)
        rs_table_for(robot, options, clock)
    # the map's preprocessing (distance transform; its size is the map's, bounded where the map is accepted) is
    # cached per map and not counted
    t_map = time.perf_counter()
    planner = planner_for(grid, robot, options)
    prepare_reachability(planner.clearance, planner.polygon)  # the flood fill's labels, also once per map
    map_s = time.perf_counter() - t_map
    limit = query.termination.time_limit_s
    remaining = limit - (clock.elapsed_s() - map_s)
    if remaining <= 0:
        raise PlannerTimedOut(f"the time limit of {limit:g} s ran out before the search started",
                              planning_time_s=limit - remaining)
    result = plan_path(grid, robot, query.start, query.goal, options, replace(query.termination,
                                                                             time_limit_s=remaining))
    # the limit covers the whole plan (smoothing, the exact re-checks, a mesh's fcl check), not only the search,
    # at every door alike
    elapsed = clock.elapsed_s() - map_s
    if elapsed > limit:
        raise PlannerTimedOut(f"the plan took {elapsed:.3g} s, over its time limit of {limit:g} s",
                              planning_time_s=elapsed, expansions=result.expansions)
    return result
