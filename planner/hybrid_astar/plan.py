"""One call from a map, a robot, a start and a goal to a verified plan.

``plan_path`` runs the spherical Hybrid A* (:mod:`planner.hybrid_astar.search`) and, when the grid was sliced from a
mesh world, re-checks the returned path exactly against the mesh with python-fcl
(:class:`planner.maps.mesh_world.MeshWorld`): the sphere and its footprint box as collision objects.
Planners are cached per (map, robot, options) so repeated queries skip the distance transform.
"""

from __future__ import annotations

import copy
from collections import OrderedDict
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

from planner.errors import NoValidPathFound
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, Pose
from planner.occupancy import OccupancyGrid
from planner.result import PlanResult
from planner.robot import RobotProfile
from planner.termination import Termination

if TYPE_CHECKING:
    from planner.maps.mesh_world import MeshWorld

_CACHE: OrderedDict[tuple[int, str, PlannerOptions], HybridAStar] = OrderedDict()
_CACHE_SIZE = 8


def planner_for(grid: OccupancyGrid, robot: RobotProfile, options: PlannerOptions | None = None) -> HybridAStar:
    """A (cached) :class:`HybridAStar` for this grid object, robot and options.

    ``improve_until_s`` only says how long a plan may look for cheaper paths: planners that differ in it alone share
    one preprocessed planner (a shallow copy carries the asked value), so a client that varies its budget per
    request does not pay the map's preprocessing again."""
    opts = options or PlannerOptions()
    if opts.improve_until_s:
        shared = copy.copy(planner_for(grid, robot, replace(opts, improve_until_s=0.0)))
        shared.options = opts
        return shared
    key = (id(grid), robot.name, opts)
    planner = _CACHE.get(key)
    if planner is None or planner.grid is not grid or planner.robot != robot:
        planner = HybridAStar(grid, robot, opts)
        _CACHE[key] = planner
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    _CACHE.move_to_end(key)
    return planner


@lru_cache(maxsize=4)
def _mesh_world(path: str) -> MeshWorld:
    from planner.maps.mesh_world import MeshWorld

    return MeshWorld.from_file(Path(path))


def mesh_recheck(grid: OccupancyGrid, robot: RobotProfile, result: PlanResult) -> dict[str, object] | None:
    """Exact fcl check of a plan on a mesh world; None when the grid did not come from a mesh."""
    if grid.mesh_path is None:
        return None
    mesh = grid.mesh_path
    world = grid.mesh_world if grid.mesh_world is not None else _mesh_world(str(mesh))
    states = result.states
    collides, index, min_distance = world.path_collides(states[:, 0], states[:, 1], states[:, 2], robot,
                                                        distance_every=10)
    return {"mesh": str(mesh), "collides": bool(collides), "first_index": index,
            "min_distance_m": float(min_distance), "distance_sampled_every": 10}


def plan_path(
    grid: OccupancyGrid, robot: RobotProfile, start: Pose, goal: Pose,
    options: PlannerOptions | None = None, termination: Termination | None = None,
) -> PlanResult:
    """Plan and verify; ``termination`` (time limit, cancel flag, iteration cap) goes unchanged to the search.
    Raises :class:`~planner.errors.PlanningError` subclasses on failure."""
    planner = planner_for(grid, robot, options)
    result = planner.plan(start, goal, termination)
    result.say_which_search(planner.reverse)
    check = mesh_recheck(grid, robot, result)
    if check is not None:
        result.extra["mesh_check"] = check
        if check["collides"]:
            raise NoValidPathFound(
                f"the path found on the sliced grid touches the mesh {check['mesh']} at state "
                f"{check['first_index']} (exact fcl check); the mesh has geometry the height slice missed",
                planning_time_s=result.planning_time_s, expansions=result.expansions,
            )
    return result
