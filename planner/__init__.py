"""sphereplan's algorithms for spherical rolling robots, one folder per paper (docs/references.md).

The public surface is this module: ``from planner import plan_path, load_map, load_robot``. Names are
imported on first use, so ``import planner`` stays cheap for the command line.

* shared kernel: errors, occupancy grid, robot profiles, sphere kinematics (paper 001 eq. 1), plan result
* :mod:`planner.maps` — nav2 map codec, catalogue, problem sets, mesh worlds, the clearance model
* :mod:`planner.hybrid_astar` — paper 001 §4.1: the spherical Hybrid A* (:func:`plan_path`)
* :mod:`planner.closed_loop` — paper 001 §3, §4.2: simulation, odometry/GNSS fusion, MPC tracking
* :mod:`planner.perception` — paper 001 §3.2–3.3: stereo obstacle points, image stabilisation
* :mod:`planner.spherobot` — paper 004: reconfiguration with P on top
* :mod:`planner.vpip` — paper 000: VPIP plane → 16 rod lengths
* :mod:`planner.tensegrity` — paper 002: TeXploR statics and gaits

Nothing here imports a transport (HTTP, Zenoh) or a wire model; ``service`` depends on ``planner``,
never the other way round.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from planner.lazy import lazy_exports

try:
    __version__ = version("sphereplan")
except PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0+unknown"

#: public name → the module that defines it
_EXPORTS: dict[str, str] = {
    # shared kernel
    "SpherePlanError": "planner.errors",
    "InvalidInput": "planner.errors",
    "MapError": "planner.errors",
    "RobotProfileError": "planner.errors",
    "NotFound": "planner.errors",
    "PlanningError": "planner.errors",
    "BadEndpoint": "planner.errors",
    "StartOutsideMap": "planner.errors",
    "GoalOutsideMap": "planner.errors",
    "StartOccupied": "planner.errors",
    "GoalOccupied": "planner.errors",
    "PlannerTimedOut": "planner.errors",
    "NoValidPathFound": "planner.errors",
    "PlannerCancelled": "planner.errors",
    "OccupancyGrid": "planner.occupancy",
    "RobotProfile": "planner.robot",
    "load_robot": "planner.robot",
    "PlanResult": "planner.result",
    # maps
    "load_map": "planner.maps.nav2",
    "save_map": "planner.maps.nav2",
    "load_any": "planner.maps.load",
    # paper 001 §4.1
    "HybridAStar": "planner.hybrid_astar.search",
    "PlannerOptions": "planner.hybrid_astar.search",
    "plan_path": "planner.hybrid_astar.plan",
    # paper 001 §3, §4.2
    "SimulationOptions": "planner.closed_loop.simulate",
    "simulate_plan": "planner.closed_loop.simulate",
    # paper 001 §3.2-3.3
    "obstacle_points": "planner.perception.stereo",
    "read_camera_info": "planner.perception.camera_info",
    "stabilise": "planner.perception.eis",
    # paper 004
    "plan_reconfiguration": "planner.spherobot.reconfigure",
    # paper 000
    "schedule_report": "planner.vpip.api",
    # paper 002
    "static_equilibria": "planner.tensegrity.statics",
    "plan_gait": "planner.tensegrity.gait",
}

__all__ = ["__version__", *_EXPORTS]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals(), __all__)
