"""A live map: a given (or unknown) map plus what the robot's sensors have seen since.

Two layers, as Nav2's costmap keeps them: the *static* layer is the map the session started from (whole-map
and region updates replace parts of it), the *observed* layer is the obstacle layer (unknown, free or
occupied per cell) that observations mark and clear (:mod:`planner.live.obstacle_layer`). The map the planner
reads is their combination: occupied where either says occupied, a static-unknown cell takes what the sensors
saw of it, everything else keeps its static value. So unknown cells stay unknown until a ray crosses them or a
point lands in them, and a clearing ray never erases a wall of the given map.

Every update returns a :class:`MapUpdate` with the rectangle of cells whose value changed, so that the
planner's distance field and heuristic are refreshed only there (:mod:`planner.live.refresh`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.ndimage import find_objects, label

from planner.errors import InvalidInput
from planner.live.observations import Observation, PointObservation, RegionUpdate, ScanObservation
from planner.live.obstacle_layer import ObstacleLayerParams
from planner.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

MAX_LIVE_CELLS = 16_000_000
"""A live map may hold at most this many cells (the 100 m × 100 m field at 5 cm is 4 M)."""
REGION_TILE_CELLS = 32
"""Changed cells are grouped into clusters of touching tiles of this many cells a side (see ``MapUpdate.regions``)."""


@dataclass(frozen=True)
class CellRect:
    """A rectangle of cells [ix0, ix1) × [iy0, iy1) (exclusive ends)."""

    ix0: int
    iy0: int
    ix1: int
    iy1: int

    @property
    def cells(self) -> int:
        return max(0, self.ix1 - self.ix0) * max(0, self.iy1 - self.iy0)

    def slices(self) -> tuple[slice, slice]:
        """Index with ``array[rect.slices()]`` (rows = y)."""
        return slice(self.iy0, self.iy1), slice(self.ix0, self.ix1)

    def expanded(self, cells: int, width: int, height: int) -> CellRect:
        """Grown by ``cells`` on every side, clipped to a ``width`` × ``height`` grid."""
        return CellRect(max(0, self.ix0 - cells), max(0, self.iy0 - cells),
                        min(width, self.ix1 + cells), min(height, self.iy1 + cells))

    def union(self, other: CellRect | None) -> CellRect:
        if other is None:
            return self
        return CellRect(min(self.ix0, other.ix0), min(self.iy0, other.iy0),
                        max(self.ix1, other.ix1), max(self.iy1, other.iy1))

    def to_json(self) -> dict[str, int]:
        return {"ix0": self.ix0, "iy0": self.iy0, "ix1": self.ix1, "iy1": self.iy1}


@dataclass(frozen=True)
class MapUpdate:
    """What one update did: ``changed`` is the smallest rectangle holding every cell whose planner-visible
    value changed (None when none did), ``regions`` the bounding rectangles of the clusters of changed cells
    (touching :data:`REGION_TILE_CELLS`-tiles: a sweep's scattered changes are a few small rectangles, not one
    big one), ``cells_changed`` how many cells changed; ``marked`` points marked, ``rays`` rays traced,
    ``time_s`` the update's wall time."""

    changed: CellRect | None
    cells_changed: int
    marked: int
    rays: int
    time_s: float
    regions: tuple[CellRect, ...] = ()

    def to_json(self) -> dict[str, object]:
        return {"changed": None if self.changed is None else self.changed.to_json(),
                "regions": [r.to_json() for r in self.regions],
                "cells_changed": self.cells_changed, "marked": self.marked, "rays": self.rays,
                "time_s": self.time_s}


@njit(cache=True)
def _trace(observed: np.ndarray, ox: float, oy: float, res: float, sx: float, sy: float,
           ex: np.ndarray, ey: np.ndarray, clear_len: np.ndarray, keep_end: np.ndarray, mark: np.ndarray,
           bounds: np.ndarray) -> None:
    """Clear each ray (sensor → end, cut at ``clear_len[i]`` m; the end cell kept when ``keep_end[i]``),
    then mark the end cells where ``mark[i]``; ``bounds`` (ix0, iy0, ix1, iy1) grows over changed cells."""
    h, w = observed.shape
    gx0 = (sx - ox) / res
    gy0 = (sy - oy) / res
    for i in range(ex.size):
        dx = ex[i] - sx
        dy = ey[i] - sy
        length = math.hypot(dx, dy)
        if clear_len[i] <= 0.0 or length <= 0.0:
            continue
        f = min(1.0, clear_len[i] / length)
        gx1 = gx0 + dx * f / res
        gy1 = gy0 + dy * f / res
        ix = int(math.floor(gx0))
        iy = int(math.floor(gy0))
        ixe = int(math.floor(gx1))
        iye = int(math.floor(gy1))
        stepx = 1 if gx1 > gx0 else -1
        stepy = 1 if gy1 > gy0 else -1
        tdx = abs(1.0 / (gx1 - gx0)) if gx1 != gx0 else math.inf
        tdy = abs(1.0 / (gy1 - gy0)) if gy1 != gy0 else math.inf
        tmx = ((ix + 1 - gx0) if stepx > 0 else (gx0 - ix)) * tdx if gx1 != gx0 else math.inf
        tmy = ((iy + 1 - gy0) if stepy > 0 else (gy0 - iy)) * tdy if gy1 != gy0 else math.inf
        n = abs(ixe - ix) + abs(iye - iy)
        last = n if not keep_end[i] or f < 1.0 else n - 1
        for k in range(n + 1):
            if k > last:
                break
            if 0 <= ix < w and 0 <= iy < h and observed[iy, ix] != 0:
                observed[iy, ix] = 0
                bounds[0] = min(bounds[0], ix)
                bounds[1] = min(bounds[1], iy)
                bounds[2] = max(bounds[2], ix + 1)
                bounds[3] = max(bounds[3], iy + 1)
            if k == n:
                break
            if tmx < tmy:
                ix += stepx
                tmx += tdx
            else:
                iy += stepy
                tmy += tdy
    for i in range(ex.size):
        if not mark[i]:
            continue
        ix = int(math.floor((ex[i] - ox) / res))
        iy = int(math.floor((ey[i] - oy) / res))
        if 0 <= ix < w and 0 <= iy < h and observed[iy, ix] != 100:
            observed[iy, ix] = 100
            bounds[0] = min(bounds[0], ix)
            bounds[1] = min(bounds[1], iy)
            bounds[2] = max(bounds[2], ix + 1)
            bounds[3] = max(bounds[3], iy + 1)


class LiveMap:
    """A given map (or an unknown one) that observations keep up to date; see the module docstring.

    :attr:`grid` is an :class:`OccupancyGrid` *view* of the combined map: its ``data`` array is updated in
    place, so a planner holding it sees every update (call :meth:`snapshot` for a copy that does not change).
    """

    def __init__(self, base: OccupancyGrid, layer: ObstacleLayerParams | None = None) -> None:
        if base.data.size > MAX_LIVE_CELLS:
            raise InvalidInput("map", f"a live map may hold at most {MAX_LIVE_CELLS} cells, this one has "
                                      f"{base.data.size}")
        self.layer = layer or ObstacleLayerParams()
        self.static: np.ndarray = np.array(base.data, dtype=np.int8, copy=True)
        self.observed: np.ndarray = np.full(self.static.shape, UNKNOWN, dtype=np.int8)
        self.threshold = int(base.occupied_threshold)
        self.grid = OccupancyGrid(data=self.static.copy(), resolution_m=base.resolution_m, origin=base.origin,
                                  occupied_threshold=base.occupied_threshold, name=base.name, source=base.source)
        self.updates = 0

    @classmethod
    def unknown(cls, width_m: float, height_m: float, resolution_m: float,
                origin: tuple[float, float, float] = (0.0, 0.0, 0.0), name: str = "unknown",
                layer: ObstacleLayerParams | None = None) -> LiveMap:
        """An all-unknown map of ``width_m`` × ``height_m`` metres."""
        for field, value in (("width_m", width_m), ("height_m", height_m), ("resolution_m", resolution_m)):
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
                raise InvalidInput(field, f"must be a finite number > 0, got {value!r}")
        w, h = math.ceil(width_m / resolution_m), math.ceil(height_m / resolution_m)
        if w * h > MAX_LIVE_CELLS:
            raise InvalidInput("width_m", f"{w} × {h} cells is over the {MAX_LIVE_CELLS}-cell limit of a live map")
        base = OccupancyGrid(np.full((h, w), UNKNOWN, dtype=np.int8), float(resolution_m), origin, name=name)
        return cls(base, layer)

    @property
    def data(self) -> np.ndarray:
        return self.grid.data

    def snapshot(self) -> OccupancyGrid:
        """A copy of the combined map as it is now."""
        g = self.grid
        return OccupancyGrid(g.data.copy(), g.resolution_m, g.origin, g.occupied_threshold, g.name, dict(g.source))

    def known_fraction(self) -> float:
        """Share of cells that are not unknown."""
        return float(np.count_nonzero(self.grid.data >= 0)) / self.grid.data.size

    # ------------------------------------------------------------------ updates

    def apply(self, observation: Observation) -> MapUpdate:
        """Apply any observation (points, scan or region)."""
        if isinstance(observation, PointObservation):
            return self.apply_points(observation)
        if isinstance(observation, ScanObservation):
            return self.apply_scan(observation)
        if isinstance(observation, RegionUpdate):
            return self.apply_region(observation)
        raise InvalidInput("observation", f"unknown observation type {type(observation).__name__}")

    def apply_points(self, obs: PointObservation) -> MapUpdate:
        """Mark the points in the height band and range, clear the rays to them (Nav2's obstacle layer)."""
        t0 = time.perf_counter()
        pts = obs.points_m
        lay = self.layer
        in_band = (pts[:, 2] >= lay.min_obstacle_height_m) & (pts[:, 2] <= lay.max_obstacle_height_m)
        pts = pts[in_band]
        dist = np.hypot(pts[:, 0] - obs.origin_m[0], pts[:, 1] - obs.origin_m[1])
        mark = (dist <= lay.obstacle_max_range_m) & (dist >= lay.obstacle_min_range_m)
        return self._rays(obs.origin_m, pts, dist, np.ones(len(pts), bool), mark, t0)

    def apply_scan(self, scan: ScanObservation) -> MapUpdate:
        """Mark each return in range, clear along every beam (no-return beams too when ``inf_is_valid``).
        The scan's points are at the sensor's height, so the height band applies to the sensor's ``z``."""
        t0 = time.perf_counter()
        origin, ends, hit = scan.rays(self.layer.inf_is_valid)
        lay = self.layer
        if not lay.min_obstacle_height_m <= scan.sensor.z <= lay.max_obstacle_height_m:
            ends, hit = ends[:0], hit[:0]
        dist = np.hypot(ends[:, 0] - origin[0], ends[:, 1] - origin[1])
        mark = hit & (dist <= lay.obstacle_max_range_m) & (dist >= lay.obstacle_min_range_m)
        return self._rays(origin, ends, dist, hit, mark, t0)

    def _rays(self, origin: np.ndarray, ends: np.ndarray, dist: np.ndarray, keep_end: np.ndarray,
              mark: np.ndarray, t0: float) -> MapUpdate:
        lay = self.layer
        clear_len = np.where(dist >= lay.raytrace_min_range_m, np.minimum(dist, lay.raytrace_max_range_m), 0.0)
        g = self.grid
        h, w = self.observed.shape
        bounds = np.array([w, h, 0, 0], dtype=np.int64)
        _trace(self.observed, float(g.origin[0]), float(g.origin[1]), g.resolution_m, float(origin[0]),
               float(origin[1]), np.ascontiguousarray(ends[:, 0]), np.ascontiguousarray(ends[:, 1]),
               np.ascontiguousarray(clear_len), np.ascontiguousarray(keep_end), np.ascontiguousarray(mark), bounds)
        rect = CellRect(*(int(b) for b in bounds)) if bounds[2] > bounds[0] else None
        return self._recombine(rect, int(np.count_nonzero(mark)), len(ends), t0)

    def apply_region(self, region: RegionUpdate) -> MapUpdate:
        """Replace the static layer in the region (and forget what the sensors saw there: the update is newer)."""
        t0 = time.perf_counter()
        h, w = self.static.shape
        rh, rw = region.data.shape
        if region.ix0 < 0 or region.iy0 < 0 or region.ix0 + rw > w or region.iy0 + rh > h:
            raise InvalidInput("data", f"the region {rw}×{rh} at ({region.ix0}, {region.iy0}) does not fit the "
                                       f"{w}×{h} map")
        rect = CellRect(region.ix0, region.iy0, region.ix0 + rw, region.iy0 + rh)
        self.static[rect.slices()] = region.data
        self.observed[rect.slices()] = UNKNOWN
        return self._recombine(rect, 0, 0, t0)

    def replace(self, grid: OccupancyGrid) -> MapUpdate:
        """A whole-map update: same size, resolution and origin as the live map."""
        g = self.grid
        if grid.data.shape != g.data.shape or not math.isclose(grid.resolution_m, g.resolution_m) or \
                not np.allclose(grid.origin, g.origin):
            raise InvalidInput("map", "a whole-map update must have the live map's size, resolution and origin "
                                      f"({g.width}×{g.height} cells at {g.resolution_m} m, origin {list(g.origin)})")
        return self.apply_region(RegionUpdate(0, 0, grid.data))

    def _recombine(self, rect: CellRect | None, marked: int, rays: int, t0: float) -> MapUpdate:
        """Recompute the combined map inside ``rect``; report the cells whose blocked-ness or value changed."""
        self.updates += 1
        if rect is None:
            return MapUpdate(None, 0, marked, rays, time.perf_counter() - t0)
        sl = rect.slices()
        static, observed = self.static[sl], self.observed[sl]
        new = np.where(static >= self.threshold, static,
                       np.where(observed == OCCUPIED, np.int8(OCCUPIED),
                                np.where((observed == FREE) & (static == UNKNOWN), np.int8(FREE), static)))
        old = self.grid.data[sl]
        diff = new != old
        if not diff.any():
            return MapUpdate(None, 0, marked, rays, time.perf_counter() - t0)
        rows, cols = np.any(diff, axis=1), np.any(diff, axis=0)
        iy = np.flatnonzero(rows)
        ix = np.flatnonzero(cols)
        old[...] = new
        tight = CellRect(rect.ix0 + int(ix[0]), rect.iy0 + int(iy[0]), rect.ix0 + int(ix[-1]) + 1,
                         rect.iy0 + int(iy[-1]) + 1)
        return MapUpdate(tight, int(diff.sum()), marked, rays, time.perf_counter() - t0, _clusters(diff, rect))


def _clusters(diff: np.ndarray, at: CellRect) -> tuple[CellRect, ...]:
    """Bounding rectangles (map cells) of the 8-connected clusters of changed tiles in ``diff`` (placed at ``at``)."""
    t = REGION_TILE_CELLS
    h, w = diff.shape
    th, tw = -(-h // t), -(-w // t)
    pad = np.zeros((th * t, tw * t), dtype=bool)
    pad[:h, :w] = diff
    tiles = pad.reshape(th, t, tw, t).any(axis=(1, 3))
    labels, _ = label(tiles, structure=np.ones((3, 3), dtype=bool))
    out = []
    for sl in find_objects(labels):
        if sl is None:
            continue
        y0, y1 = sl[0].start * t, min(h, sl[0].stop * t)
        x0, x1 = sl[1].start * t, min(w, sl[1].stop * t)
        block = diff[y0:y1, x0:x1]
        ry, rx = np.flatnonzero(block.any(axis=1)), np.flatnonzero(block.any(axis=0))
        out.append(CellRect(at.ix0 + x0 + int(rx[0]), at.iy0 + y0 + int(ry[0]),
                            at.ix0 + x0 + int(rx[-1]) + 1, at.iy0 + y0 + int(ry[-1]) + 1))
    return tuple(out)
