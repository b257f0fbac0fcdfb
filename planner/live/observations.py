"""What a sensor tells the live map: obstacle points with the sensor's origin, a laser scan, or a map region.

These are the value types the doors build from their messages (``sensor_msgs/PointCloud2``,
``sensor_msgs/LaserScan``, ``nav_msgs/OccupancyGrid`` or their JSON forms) and what stereo perception
(``planner/perception``) feeds. Every array is checked when the value is made (:class:`InvalidInput`
naming the field); all coordinates are metres in the ``map`` frame unless a :class:`SensorPose` says
otherwise (REP-103: x forward, y left, z up; the ground is z = 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.angles import check_angle
from planner.errors import InvalidInput

MAX_POINTS = 1_000_000
"""The most points (or scan beams) one observation may carry; the doors set tighter limits."""


def _finite(value: float, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InvalidInput(field, f"must be a finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class SensorPose:
    """Pose of a sensor in the map frame: position (m) and yaw, pitch, roll (rad, ZYX: yaw about z first).

    A planar range sensor mounted on the sphere sits at ``z`` = its mounting height above the ground.
    """

    x: float
    y: float
    z: float = 0.0
    yaw: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "z", "yaw", "pitch", "roll"):
            value = _finite(getattr(self, name), f"sensor_pose.{name}")
            if name in ("yaw", "pitch", "roll"):
                check_angle(f"sensor_pose.{name}", value, "degrees converted to radians")

    def rotation(self) -> np.ndarray:
        """The 3×3 rotation from the sensor frame to the map frame (R = Rz(yaw)·Ry(pitch)·Rx(roll))."""
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
        rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
        return rz @ ry @ rx

    def to_map(self, points: np.ndarray) -> np.ndarray:
        """Points (n, 3) in the sensor frame → the map frame."""
        return np.asarray(points, float) @ self.rotation().T + np.array([self.x, self.y, self.z])


@dataclass(frozen=True, eq=False)
class PointObservation:
    """Obstacle points seen from one sensor origin, both in the map frame.

    Parameters
    ----------
    points_m : (n, 3) float array, x, y, z in metres (z above the ground).
    origin_m : (3,) the sensor's position when it saw them; rays from here to each point are cleared.
    """

    points_m: np.ndarray
    origin_m: np.ndarray

    def __post_init__(self) -> None:
        pts = np.asarray(self.points_m, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise InvalidInput("points", f"must be an (n, 3) array of x, y, z, got shape {pts.shape}")
        if len(pts) > MAX_POINTS:
            raise InvalidInput("points", f"at most {MAX_POINTS} points per observation, got {len(pts)}")
        if not np.all(np.isfinite(pts)):
            raise InvalidInput("points", "must be finite numbers (drop NaN points before sending)")
        origin = np.asarray(self.origin_m, dtype=float).reshape(-1)
        if origin.shape != (3,) or not np.all(np.isfinite(origin)):
            raise InvalidInput("origin", f"must be three finite numbers x, y, z, got {self.origin_m!r}")
        object.__setattr__(self, "points_m", pts)
        object.__setattr__(self, "origin_m", origin)

    @classmethod
    def in_sensor_frame(cls, points_m: np.ndarray, sensor: SensorPose) -> PointObservation:
        """Points (n, 3) given in the sensor's frame, the sensor at ``sensor`` in the map frame."""
        pts = np.asarray(points_m, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise InvalidInput("points", f"must be an (n, 3) array of x, y, z, got shape {pts.shape}")
        return cls(sensor.to_map(pts), np.array([sensor.x, sensor.y, sensor.z]))


@dataclass(frozen=True, eq=False)
class ScanObservation:
    """A planar laser scan (``sensor_msgs/LaserScan``): beam i points at ``angle_min + i·angle_increment``
    (rad, in the sensor frame) and returned ``ranges_m[i]``; inf or > ``range_max_m`` means no return,
    NaN or < ``range_min_m`` an invalid beam (ignored)."""

    ranges_m: np.ndarray
    angle_min_rad: float
    angle_increment_rad: float
    range_min_m: float
    range_max_m: float
    sensor: SensorPose

    def __post_init__(self) -> None:
        ranges = np.asarray(self.ranges_m, dtype=float).reshape(-1)
        if len(ranges) > MAX_POINTS:
            raise InvalidInput("ranges", f"at most {MAX_POINTS} beams per scan, got {len(ranges)}")
        if np.any(ranges < 0):
            raise InvalidInput("ranges", "must be ≥ 0 (inf for no return)")
        check_angle("angle_min", _finite(self.angle_min_rad, "angle_min"), "degrees converted to radians")
        check_angle("angle_increment", _finite(self.angle_increment_rad, "angle_increment"),
                    "degrees converted to radians")
        lo, hi = _finite(self.range_min_m, "range_min"), _finite(self.range_max_m, "range_max")
        if not 0 <= lo < hi:
            raise InvalidInput("range_max", f"must be > range_min ≥ 0, got range_min={lo}, range_max={hi}")
        object.__setattr__(self, "ranges_m", ranges)

    def rays(self, inf_is_valid: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The scan as rays in the map frame: (origin (3,), ends (m, 3), hit (m,) bool).

        A beam with a return in [range_min, range_max] ends at its hit point (``hit`` True); a beam with no
        return (inf or beyond range_max) ends at ``range_max`` with ``hit`` False when ``inf_is_valid``
        (Nav2's obstacle layer option: it then clears along the whole beam), and is dropped otherwise.
        """
        r = self.ranges_m
        angles = self.angle_min_rad + self.angle_increment_rad * np.arange(len(r))
        valid = np.isfinite(r) & (r >= self.range_min_m) & (r <= self.range_max_m)
        no_return = (np.isinf(r) | (r > self.range_max_m)) & ~np.isnan(r)
        use = valid | (no_return & inf_is_valid)
        dist = np.where(valid, r, self.range_max_m)[use]
        a = angles[use]
        local = np.stack([dist * np.cos(a), dist * np.sin(a), np.zeros_like(dist)], axis=1)
        ends = self.sensor.to_map(local)
        return np.array([self.sensor.x, self.sensor.y, self.sensor.z]), ends, valid[use]


@dataclass(frozen=True, eq=False)
class RegionUpdate:
    """New map values for a rectangle of cells (``nav_msgs/OccupancyGrid`` or map_msgs' OccupancyGridUpdate):
    ``data[iy, ix]`` (0..100 or −1, row 0 at the bottom) replaces the cells from (``ix0``, ``iy0``)."""

    ix0: int
    iy0: int
    data: np.ndarray

    def __post_init__(self) -> None:
        for name in ("ix0", "iy0"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer):
                raise InvalidInput(name, f"must be an integer cell index, got {value!r}")
        data = np.asarray(self.data)
        if data.ndim != 2 or data.size == 0:
            raise InvalidInput("data", f"must be a non-empty 2-D grid, got shape {data.shape}")
        if not np.issubdtype(data.dtype, np.number) or not np.all(np.isfinite(data)):
            raise InvalidInput("data", "must hold numbers")
        if np.any((data < -1) | (data > 100)) or np.any(data != np.round(data)):
            raise InvalidInput("data", "cells must be integers in 0..100 or -1 (unknown)")
        object.__setattr__(self, "data", data.astype(np.int8))


Observation = PointObservation | ScanObservation | RegionUpdate
"""Anything :meth:`planner.live.live_map.LiveMap.apply` takes."""
