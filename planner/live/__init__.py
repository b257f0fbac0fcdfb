"""Live maps and replanning: explore a world nobody mapped (Nav2's obstacle layer + planner server, issue 22).

* :mod:`~planner.live.observations` — what sensors report: points + sensor origin, laser scans, map regions;
* :mod:`~planner.live.obstacle_layer` — Nav2's marking/clearing parameters, paper 001's height and range filter;
* :mod:`~planner.live.live_map` — the live map (static layer + obstacle layer) and the changed rectangle;
* :mod:`~planner.live.refresh` — refresh a planner's distance field and heuristic for the changed cells;
* :mod:`~planner.live.session` — goal, pose and path of one robot, replanned when blocked or on a timer;
* :mod:`~planner.live.guide` — a heuristic that closes the gaps the robot cannot roll through, for replans;
* :mod:`~planner.live.range_sensor` — a simulated range sensor ray-cast in a true world.

The closed-loop exploration run that uses them all is :mod:`planner.closed_loop.explore`.
"""

from planner.live.live_map import CellRect, LiveMap, MapUpdate
from planner.live.observations import Observation, PointObservation, RegionUpdate, ScanObservation, SensorPose
from planner.live.obstacle_layer import ObstacleLayerParams
from planner.live.range_sensor import RangeSensor
from planner.live.refresh import refresh
from planner.live.session import LiveSession, ReplanEvent, ReplanPolicy, live_options

__all__ = [
    "CellRect",
    "LiveMap",
    "LiveSession",
    "MapUpdate",
    "Observation",
    "ObstacleLayerParams",
    "PointObservation",
    "RangeSensor",
    "RegionUpdate",
    "ReplanEvent",
    "ReplanPolicy",
    "ScanObservation",
    "SensorPose",
    "live_options",
    "refresh",
]
