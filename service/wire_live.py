"""Strict Pydantic wire models of the robot-session doors (HTTP ``/v1/sessions``, Zenoh ``sphereplan/<id>/live/*``).

Kept apart from the planner's types: each model checks its JSON (unknown fields, wrong types, NaN/inf refused,
sizes bounded) and turns into the planner's value (:mod:`planner.live.observations`) with one method. A scan's
``null`` range means "no return" (JSON has no infinity).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, model_validator

from planner.errors import InvalidInput
from planner.live.observations import Observation, PointObservation, RegionUpdate, ScanObservation, SensorPose
from planner.live.obstacle_layer import ObstacleLayerParams
from planner.live.session import ReplanPolicy
from service.wire import Angle, MapSpec, Metres, Name, PoseIn, _Strict

MAX_WIRE_POINTS = 100_000
MAX_WIRE_BEAMS = 10_000
MAX_WIRE_REGION_ROWS = 2_000

Point3 = Annotated[list[Metres], Field(min_length=3, max_length=3)]


class UnknownArea(_Strict):
    """An all-unknown map of ``width_m`` × ``height_m`` with its lower-left corner at ``origin``."""

    width_m: float = Field(gt=0, le=2000)
    height_m: float = Field(gt=0, le=2000)
    resolution_m: float = Field(ge=0.01, le=10)
    origin: list[Metres] = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3)


class LayerIn(_Strict):
    """Nav2 obstacle-layer parameters (:class:`planner.live.obstacle_layer.ObstacleLayerParams`); unset = paper 001's
    filter for the robot (≥ 5 cm, at most the sphere's diameter high, within 10 m)."""

    obstacle_max_range_m: float | None = Field(default=None, gt=0, le=100)
    raytrace_max_range_m: float | None = Field(default=None, gt=0, le=100)
    min_obstacle_height_m: float | None = Field(default=None, ge=-10, le=100)
    max_obstacle_height_m: float | None = Field(default=None, ge=-10, le=100)
    inf_is_valid: bool | None = None

    def params(self, base: ObstacleLayerParams) -> ObstacleLayerParams:
        given = {k: v for k, v in self.model_dump().items() if v is not None}
        return ObstacleLayerParams(**{**base.__dict__, **given})


class SessionCreate(_Strict):
    """A new robot session: ``map`` (a name, an inline grid or a ``nav_msgs/OccupancyGrid``) or ``unknown`` (an
    area nobody mapped), the robot's ``start`` pose, optionally its ``goal`` (planned at once)."""

    map: MapSpec | None = None
    unknown: UnknownArea | None = None
    robot: Name | None = None
    start: PoseIn
    goal: PoseIn | None = None
    options: dict[str, Any] | None = Field(
        default=None, description="planner options; allow_unknown defaults to true and greed to 2 (live_options)")
    time_limit_s: float | None = Field(default=None, gt=0, le=10, description="each replan's time limit (default 2 s)")
    replan_period_s: float | None = Field(default=None, ge=0.1, le=3600, description="also replan this often")
    layer: LayerIn | None = None
    id: Name | None = Field(default=None, description="the session's id (default: a random one)")

    @model_validator(mode="after")
    def _one_map(self) -> SessionCreate:
        if (self.map is None) == (self.unknown is None):
            raise ValueError("give exactly one of map and unknown")
        return self

    def policy(self) -> ReplanPolicy:
        """The session's replan policy: the time limit and period asked for, ReplanPolicy's defaults for the rest
        (the one place every door makes it)."""
        return ReplanPolicy(self.replan_period_s, ReplanPolicy.time_limit_s if self.time_limit_s is None
                            else self.time_limit_s)


class SensorPoseIn(_Strict):
    """A sensor's pose in the map frame: position (m), yaw, pitch, roll (rad)."""

    x: Metres
    y: Metres
    z: Metres = 0.0
    yaw: Angle = 0.0
    pitch: Angle = 0.0
    roll: Angle = 0.0

    def value(self) -> SensorPose:
        return SensorPose(self.x, self.y, self.z, self.yaw, self.pitch, self.roll)


class PointsIn(_Strict):
    """Obstacle points: in the ``map`` frame with the sensor's ``origin`` [x, y, z], or in the ``sensor`` frame with
    its ``sensor_pose`` (the origin is then the sensor's position)."""

    points: list[Point3] = Field(max_length=MAX_WIRE_POINTS)
    frame: Literal["map", "sensor"] = "map"
    origin: Point3 | None = None
    sensor_pose: SensorPoseIn | None = None

    @model_validator(mode="after")
    def _frame(self) -> PointsIn:
        if self.frame == "sensor" and self.sensor_pose is None:
            raise ValueError("points in the sensor frame need sensor_pose")
        if self.frame == "map" and self.origin is None and self.sensor_pose is None:
            raise ValueError("points in the map frame need origin (the sensor's position) or sensor_pose")
        return self

    def value(self) -> PointObservation:
        pts = np.asarray(self.points, dtype=float).reshape(-1, 3)
        if self.frame == "sensor":
            assert self.sensor_pose is not None
            return PointObservation.in_sensor_frame(pts, self.sensor_pose.value())
        if self.origin is not None:
            return PointObservation(pts, np.asarray(self.origin, dtype=float))
        assert self.sensor_pose is not None
        s = self.sensor_pose
        return PointObservation(pts, np.array([s.x, s.y, s.z]))


class ScanIn(_Strict):
    """A planar laser scan (``sensor_msgs/LaserScan``): ``ranges[i]`` at ``angle_min + i·angle_increment`` in the
    sensor frame; ``null`` = no return."""

    ranges: list[Annotated[float, Field(ge=0, le=1e4)] | None] = Field(min_length=1, max_length=MAX_WIRE_BEAMS)
    angle_min: Angle
    angle_increment: Angle
    range_min: float = Field(default=0.0, ge=0, le=1e4)
    range_max: float = Field(gt=0, le=1e4)
    sensor_pose: SensorPoseIn

    def value(self) -> ScanObservation:
        ranges = np.array([np.inf if r is None else r for r in self.ranges], dtype=float)
        return ScanObservation(ranges, self.angle_min, self.angle_increment, self.range_min, self.range_max,
                               self.sensor_pose.value())


class RegionIn(_Strict):
    """New values for a rectangle of cells from (``ix0``, ``iy0``): ``data[iy][ix]`` in 0..100 or −1, row 0 at the
    bottom."""

    ix0: int = Field(ge=0, le=1_000_000)
    iy0: int = Field(ge=0, le=1_000_000)
    data: list[list[Annotated[int, Field(ge=-1, le=100)]]] = Field(min_length=1, max_length=MAX_WIRE_REGION_ROWS)

    @model_validator(mode="after")
    def _rectangular(self) -> RegionIn:
        width = len(self.data[0])
        if width == 0 or any(len(row) != width for row in self.data):
            raise ValueError("data must be a non-empty rectangular list of rows")
        return self

    def value(self) -> RegionUpdate:
        return RegionUpdate(self.ix0, self.iy0, np.asarray(self.data, dtype=np.int8))


class ObservationIn(_Strict):
    """One observation: exactly one of ``points``, ``scan`` and ``region``."""

    points: PointsIn | None = None
    scan: ScanIn | None = None
    region: RegionIn | None = None

    @model_validator(mode="after")
    def _one(self) -> ObservationIn:
        if sum(v is not None for v in (self.points, self.scan, self.region)) != 1:
            raise ValueError("give exactly one of points, scan and region")
        return self

    def value(self) -> Observation:
        """The planner's observation; a value the planner refuses is named under this message's part
        (``scan.sensor_pose.yaw``, ``region.data``)."""
        name = "points" if self.points is not None else "scan" if self.scan is not None else "region"
        part = self.points or self.scan or self.region
        assert part is not None
        try:
            return part.value()
        except InvalidInput as exc:
            raise InvalidInput(f"{name}.{exc.field}", exc.msg) from None
