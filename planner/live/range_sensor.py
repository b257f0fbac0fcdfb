"""A simulated planar range sensor: beams ray-cast in a true map from the robot's true pose.

It stands in for the robot's stereo camera or lidar when ``sphereplan explore`` rolls the sphere through a
world the planner does not know: each beam stops at the first blocked cell of the *true* map (occupied, or
unknown unless the world allows it: what the robot cannot enter it also cannot see through) and returns that
distance with seeded Gaussian noise, or no return (inf) within ``range_m``. The scan it returns goes through
the live map's obstacle-layer filters like any real one (paper 001 §3.3: obstacles 5 cm .. the sphere's
diameter high, within 10 m; the sensor is mounted at the sphere's centre height).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from planner.errors import InvalidInput
from planner.live.observations import ScanObservation, SensorPose
from planner.occupancy import OccupancyGrid


@njit(cache=True)
def _cast(blocked: np.ndarray, ox: float, oy: float, res: float, sx: float, sy: float, angles: np.ndarray,
          range_m: float) -> np.ndarray:
    """Distance (m) along each beam to the first blocked cell (half a cell past its entry point, so that the
    return lies inside the cell that stopped it), inf when none is in range; leaving the map is no return."""
    h, w = blocked.shape
    out = np.full(angles.size, np.inf)
    gx0 = (sx - ox) / res
    gy0 = (sy - oy) / res
    for i in range(angles.size):
        dx = math.cos(angles[i])
        dy = math.sin(angles[i])
        ix = int(math.floor(gx0))
        iy = int(math.floor(gy0))
        stepx = 1 if dx > 0 else -1
        stepy = 1 if dy > 0 else -1
        tdx = abs(res / dx) if dx != 0.0 else math.inf
        tdy = abs(res / dy) if dy != 0.0 else math.inf
        tmx = ((ix + 1 - gx0) if stepx > 0 else (gx0 - ix)) * tdx if dx != 0.0 else math.inf
        tmy = ((iy + 1 - gy0) if stepy > 0 else (gy0 - iy)) * tdy if dy != 0.0 else math.inf
        t = 0.0
        while t <= range_m:
            if ix < 0 or iy < 0 or ix >= w or iy >= h:
                break
            if blocked[iy, ix]:
                out[i] = t + 0.5 * res
                break
            if tmx < tmy:
                t = tmx
                ix += stepx
                tmx += tdx
            else:
                t = tmy
                iy += stepy
                tmy += tdy
    return out


@dataclass(frozen=True)
class RangeSensor:
    """``n_beams`` beams over ``fov_rad`` (centred on the heading), ``range_m`` reach, Gaussian range noise
    ``noise_m`` (1σ), mounted ``height_m`` above the ground."""

    range_m: float = 10.0
    n_beams: int = 720
    fov_rad: float = 2.0 * math.pi
    noise_m: float = 0.01
    height_m: float = 0.3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.range_m) and 0 < self.range_m <= 100):
            raise InvalidInput("sensor_range", f"must be in (0, 100] m, got {self.range_m!r}")
        if not 1 <= self.n_beams <= 100_000:
            raise InvalidInput("n_beams", f"must be in [1, 100 000], got {self.n_beams!r}")
        if not 0 < self.fov_rad <= 2 * math.pi:
            raise InvalidInput("fov_rad", "must be in (0, 2π]")

    def scan(self, world: OccupancyGrid, pose: tuple[float, float, float], rng: np.random.Generator,
             allow_unknown: bool = False) -> ScanObservation:
        """One sweep from ``pose`` (x, y, yaw: the robot's true pose) through ``world``."""
        full = self.fov_rad >= 2 * math.pi - 1e-9
        inc = self.fov_rad / (self.n_beams if full else max(1, self.n_beams - 1))
        angle_min = 0.0 if full else -self.fov_rad / 2
        rel = angle_min + inc * np.arange(self.n_beams)
        x, y, yaw = pose
        dist = _cast(world.blocked(allow_unknown), float(world.origin[0]), float(world.origin[1]),
                     world.resolution_m, float(x), float(y), np.ascontiguousarray(rel + yaw), self.range_m)
        hit = np.isfinite(dist)
        if self.noise_m > 0 and hit.any():
            dist[hit] = np.maximum(dist[hit] + rng.normal(0.0, self.noise_m, int(hit.sum())), 0.0)
        dist[hit & (dist > self.range_m)] = np.inf
        return ScanObservation(dist, angle_min, inc, 0.0, self.range_m,
                               SensorPose(float(x), float(y), self.height_m, wrap_yaw(yaw)))


def wrap_yaw(yaw: float) -> float:
    """Yaw wrapped to (−π, π]."""
    return math.atan2(math.sin(yaw), math.cos(yaw))
