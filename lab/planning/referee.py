"""The real-map benchmark's own exact footprint check: a robot's padded polygon against the occupancy grid.

This module is the benchmark's measuring instrument, written apart from the planner's collision model
(:mod:`planner.maps.clearance`: covering circles on a distance transform) so that it can judge it. A pose
``(x, y, yaw)`` places :attr:`~planner.robot.RobotProfile.footprint_polygon` (the padded polygon in the robot
frame, Nav2 convention: x forward, y left) in the map frame; then

* every blocked cell is the closed square ``[ox + ix·res, ox + (ix+1)·res] × [oy + iy·res, oy + (iy+1)·res]``
  (occupied cells; unknown cells too unless ``allow_unknown``), and the pose **collides** when the closed
  polygon and a blocked square share a point (touching counts);
* the polygon must lie inside the map rectangle: a vertex outside it collides (leaving the map collides);
* the **clearance** of a free pose is the exact Euclidean distance from the polygon to the nearest blocked
  square or to the map's edge (vertex-to-edge distances of the two polygons), capped at ``reach_m``.

Both tests are exact for any simple polygon (convex or not). A pose check looks only at the blocked cells
under the polygon's bounding box, and skips a cell at once when its centre is farther from the robot's
centre than the polygon's circumradius plus half a cell diagonal; the kernels are compiled with numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile

DEFAULT_REACH_M = 2.0  # clearances are capped here, as the plan's reported clearance is (a test holds them equal)


@njit(cache=True)
def _place(poly: np.ndarray, x: float, y: float, yaw: float, out: np.ndarray) -> None:
    """Polygon vertices (n, 2) in the robot frame → map frame, written into ``out``."""
    c, s = math.cos(yaw), math.sin(yaw)
    for k in range(poly.shape[0]):
        out[k, 0] = x + c * poly[k, 0] - s * poly[k, 1]
        out[k, 1] = y + s * poly[k, 0] + c * poly[k, 1]


@njit(cache=True)
def _segment_meets_box(ax: float, ay: float, bx: float, by: float,
                       x0: float, y0: float, x1: float, y1: float) -> bool:
    """Does the closed segment a→b meet the closed axis-aligned box [x0, x1] × [y0, y1]? (Liang–Barsky)"""
    dx, dy = bx - ax, by - ay
    t0, t1 = 0.0, 1.0
    for i in range(4):
        if i == 0:
            p, q = -dx, ax - x0
        elif i == 1:
            p, q = dx, x1 - ax
        elif i == 2:
            p, q = -dy, ay - y0
        else:
            p, q = dy, y1 - ay
        if p == 0.0:
            if q < 0.0:
                return False
        else:
            r = q / p
            if p < 0.0:
                if r > t0:
                    t0 = r
            elif r < t1:
                t1 = r
            if t0 > t1:
                return False
    return True


@njit(cache=True)
def _inside(pts: np.ndarray, px: float, py: float) -> bool:
    """Even–odd point-in-polygon test (the point is assumed off the boundary)."""
    n = pts.shape[0]
    inside = False
    j = n - 1
    for i in range(n):
        yi, yj = pts[i, 1], pts[j, 1]
        if (yi > py) != (yj > py):
            xc = pts[i, 0] + (py - yi) * (pts[j, 0] - pts[i, 0]) / (yj - yi)
            if px < xc:
                inside = not inside
        j = i
    return inside


@njit(cache=True)
def _polygon_meets_box(pts: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> bool:
    """Do the closed polygon ``pts`` and the closed box share a point?

    Either an edge of the polygon meets the box (this covers a vertex inside the box and crossing
    boundaries), or no edge does and the box lies wholly inside or wholly outside: test its centre.
    """
    n = pts.shape[0]
    for k in range(n):
        m = k + 1 if k + 1 < n else 0
        if _segment_meets_box(pts[k, 0], pts[k, 1], pts[m, 0], pts[m, 1], x0, y0, x1, y1):
            return True
    return _inside(pts, 0.5 * (x0 + x1), 0.5 * (y0 + y1))


@njit(cache=True)
def _collides(pts: np.ndarray, cx: float, cy: float, blocked: np.ndarray, ox: float, oy: float, res: float,
              circumradius: float) -> bool:
    """Exact collision of the placed polygon ``pts`` (centre cx, cy) with the grid; leaving the map collides."""
    h, w = blocked.shape
    x_max, y_max = ox + w * res, oy + h * res
    min_x, min_y, max_x, max_y = np.inf, np.inf, -np.inf, -np.inf
    for k in range(pts.shape[0]):
        px, py = pts[k, 0], pts[k, 1]
        if px < ox or px > x_max or py < oy or py > y_max:
            return True
        min_x, max_x = min(min_x, px), max(max_x, px)
        min_y, max_y = min(min_y, py), max(max_y, py)
    ix0 = max(int(math.floor((min_x - ox) / res)) - 1, 0)
    ix1 = min(int(math.floor((max_x - ox) / res)) + 1, w - 1)
    iy0 = max(int(math.floor((min_y - oy) / res)) - 1, 0)
    iy1 = min(int(math.floor((max_y - oy) / res)) + 1, h - 1)
    reach = circumradius + res * 0.7072  # a square farther than this from the centre cannot meet the polygon
    reach2 = reach * reach
    for iy in range(iy0, iy1 + 1):
        y0 = oy + iy * res
        dy = y0 + 0.5 * res - cy
        for ix in range(ix0, ix1 + 1):
            if not blocked[iy, ix]:
                continue
            x0 = ox + ix * res
            dx = x0 + 0.5 * res - cx
            if dx * dx + dy * dy > reach2:
                continue
            if _polygon_meets_box(pts, x0, y0, x0 + res, y0 + res):
                return True
    return False


@njit(cache=True)
def _point_box(px: float, py: float, x0: float, y0: float, x1: float, y1: float) -> float:
    """Distance from a point to a closed axis-aligned box."""
    dx = max(x0 - px, 0.0, px - x1)
    dy = max(y0 - py, 0.0, py - y1)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True)
def _point_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    abx, aby = bx - ax, by - ay
    den = abx * abx + aby * aby
    t = 0.0 if den <= 0.0 else min(max(((px - ax) * abx + (py - ay) * aby) / den, 0.0), 1.0)
    ex, ey = ax + t * abx - px, ay + t * aby - py
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def _clearance(pts: np.ndarray, cx: float, cy: float, blocked: np.ndarray, ox: float, oy: float, res: float,
               circumradius: float, cap: float, ring_dx: np.ndarray, ring_dy: np.ndarray,
               ring_d: np.ndarray) -> float:
    """Exact distance (m) from the placed polygon to the nearest blocked square or the map's edge, ≤ ``cap``;
    0 when the pose collides.

    ``ring_dx, ring_dy`` are cell offsets from the centre's cell sorted by ``ring_d`` (their length, m): cells
    are visited nearest first and the scan stops once no farther cell can beat the best distance found.
    """
    if _collides(pts, cx, cy, blocked, ox, oy, res, circumradius):
        return 0.0
    h, w = blocked.shape
    x_max, y_max = ox + w * res, oy + h * res
    best = cap
    n = pts.shape[0]
    for k in range(n):  # distance to the map's edge: a concave function inside the rectangle, least at a vertex
        px, py = pts[k, 0], pts[k, 1]
        best = min(best, px - ox, x_max - px, py - oy, y_max - py)
    icx = int(math.floor((cx - ox) / res))
    icy = int(math.floor((cy - oy) / res))
    half_diag = res * 0.7072
    for j in range(ring_d.shape[0]):
        # the pose's centre is within half a diagonal of its cell's centre, the square within half a diagonal
        # of its own centre, and no point of the polygon is farther than circumradius from the pose's centre
        if ring_d[j] - 2.0 * half_diag - circumradius >= best:
            break
        ix, iy = icx + ring_dx[j], icy + ring_dy[j]
        if ix < 0 or iy < 0 or ix >= w or iy >= h or not blocked[iy, ix]:
            continue
        x0, y0 = ox + ix * res, oy + iy * res
        x1, y1 = x0 + res, y0 + res
        d = best
        for k in range(n):  # polygon vertices to the square
            d = min(d, _point_box(pts[k, 0], pts[k, 1], x0, y0, x1, y1))
        for k in range(n):  # square corners to the polygon's edges
            m = k + 1 if k + 1 < n else 0
            ax, ay, bx, by = pts[k, 0], pts[k, 1], pts[m, 0], pts[m, 1]
            d = min(d, _point_segment(x0, y0, ax, ay, bx, by), _point_segment(x1, y0, ax, ay, bx, by),
                    _point_segment(x1, y1, ax, ay, bx, by), _point_segment(x0, y1, ax, ay, bx, by))
        best = min(best, d)
    return best


@njit(cache=True)
def _collides_poses(poly: np.ndarray, poses: np.ndarray, blocked: np.ndarray, ox: float, oy: float, res: float,
                    circumradius: float) -> np.ndarray:
    out = np.zeros(poses.shape[0], dtype=np.bool_)
    pts = np.empty_like(poly)
    for i in range(poses.shape[0]):
        _place(poly, poses[i, 0], poses[i, 1], poses[i, 2], pts)
        out[i] = _collides(pts, poses[i, 0], poses[i, 1], blocked, ox, oy, res, circumradius)
    return out


@njit(cache=True)
def _collides_pose(poly: np.ndarray, x: float, y: float, yaw: float, blocked: np.ndarray, ox: float, oy: float,
                   res: float, circumradius: float) -> bool:
    pts = np.empty_like(poly)
    _place(poly, x, y, yaw, pts)
    return _collides(pts, x, y, blocked, ox, oy, res, circumradius)


@njit(cache=True)
def _clearance_poses(poly: np.ndarray, poses: np.ndarray, blocked: np.ndarray, ox: float, oy: float, res: float,
                     circumradius: float, cap: float, ring_dx: np.ndarray, ring_dy: np.ndarray,
                     ring_d: np.ndarray) -> np.ndarray:
    out = np.empty(poses.shape[0])
    pts = np.empty_like(poly)
    for i in range(poses.shape[0]):
        _place(poly, poses[i, 0], poses[i, 1], poses[i, 2], pts)
        out[i] = _clearance(pts, poses[i, 0], poses[i, 1], blocked, ox, oy, res, circumradius, cap,
                            ring_dx, ring_dy, ring_d)
    return out


def _rings(resolution_m: float, radius_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell offsets (dx, dy) within ``radius_m`` (plus two cells) of a cell, nearest first, with their lengths (m)."""
    k = int(math.ceil(radius_m / resolution_m)) + 2
    dy, dx = np.mgrid[-k:k + 1, -k:k + 1]
    d = np.hypot(dx, dy).ravel() * resolution_m
    keep = d <= radius_m + 2 * resolution_m * 0.7072
    order = np.argsort(d[keep], kind="stable")
    return (dx.ravel()[keep][order].astype(np.int64), dy.ravel()[keep][order].astype(np.int64),
            d[keep][order].copy())


@dataclass(frozen=True, eq=False)
class FootprintReferee:
    """Exact footprint-polygon collision and clearance on one grid.

    Parameters
    ----------
    polygon : float array (n, 2)
        The footprint in the robot frame (x forward, y left), metres, padding included; a simple polygon
        around the robot's centre.
    blocked : bool array (height, width)
        True where the robot may not be (row 0 at the bottom, as in :class:`~planner.occupancy.OccupancyGrid`).
    origin_xy : (float, float)
        Map coordinates (m) of the lower-left corner of cell (0, 0).
    resolution_m : float
        Cell side (m).
    """

    polygon: np.ndarray
    blocked: np.ndarray
    origin_xy: tuple[float, float]
    resolution_m: float

    @classmethod
    def for_robot(cls, grid: OccupancyGrid, robot: RobotProfile, allow_unknown: bool = False) -> FootprintReferee:
        """The checker for ``robot.footprint_polygon`` on ``grid`` (unknown cells block unless allowed)."""
        return cls(
            polygon=np.ascontiguousarray(robot.footprint_polygon, dtype=np.float64),
            blocked=np.ascontiguousarray(grid.blocked(allow_unknown)),
            origin_xy=(float(grid.origin[0]), float(grid.origin[1])),
            resolution_m=float(grid.resolution_m),
        )

    @property
    def circumradius_m(self) -> float:
        """Largest distance (m) from the robot's centre to a polygon vertex."""
        return float(np.hypot(self.polygon[:, 0], self.polygon[:, 1]).max())

    @property
    def inradius_m(self) -> float:
        """Radius (m) of the largest disc about the robot's centre inside the polygon (distance to its edges)."""
        a = self.polygon
        b = np.roll(a, -1, axis=0)
        ab = b - a
        t = np.clip(-(a * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
        return float(np.hypot(*(a + t[:, None] * ab).T).min())

    def collides(self, x: float, y: float, yaw: float) -> bool:
        """True when the polygon at pose (x m, y m, yaw rad) meets a blocked cell or leaves the map."""
        return bool(_collides_pose(self.polygon, float(x), float(y), float(yaw), self.blocked, self.origin_xy[0],
                                   self.origin_xy[1], self.resolution_m, self.circumradius_m))

    def collides_many(self, poses: np.ndarray) -> np.ndarray:
        """:meth:`collides` for every row (x, y, yaw, ...) of ``poses`` (n, ≥ 3); a bool array (n,)."""
        p = np.ascontiguousarray(np.asarray(poses, dtype=np.float64)[:, :3])
        return _collides_poses(self.polygon, p, self.blocked, self.origin_xy[0], self.origin_xy[1],
                               self.resolution_m, self.circumradius_m)

    def clearances(self, poses: np.ndarray, reach_m: float = DEFAULT_REACH_M) -> np.ndarray:
        """Exact distance (m) from the polygon at each pose to the nearest blocked square or the map's edge,
        capped at ``reach_m``; 0 where the pose collides. ``poses``: (n, ≥ 3) rows x, y, yaw."""
        p = np.ascontiguousarray(np.asarray(poses, dtype=np.float64)[:, :3])
        ring_dx, ring_dy, ring_d = _rings(self.resolution_m, self.circumradius_m + float(reach_m) + self.resolution_m)
        return _clearance_poses(self.polygon, p, self.blocked, self.origin_xy[0], self.origin_xy[1],
                                self.resolution_m, self.circumradius_m, float(reach_m), ring_dx, ring_dy, ring_d)

    def min_clearance(self, poses: np.ndarray, reach_m: float = DEFAULT_REACH_M) -> float:
        """Smallest :meth:`clearances` along ``poses`` (m); ``nan`` for no poses."""
        if len(poses) == 0:
            return math.nan
        return float(self.clearances(poses, reach_m).min())

    def grown(self, pad_m: float) -> FootprintReferee:
        """The referee for the polygon grown by ``pad_m`` (:func:`grown_polygon`): a pose it calls free keeps the
        original polygon at least ``pad_m`` − :data:`GROWTH_ERROR` × ``pad_m`` from every blocked square and from the
        map's edge (the room a planner is asked to keep, as the benchmark's room-matched reference does)."""
        return replace(self, polygon=grown_polygon(self.polygon, pad_m))


GROWTH_SAMPLES = 64  # points on the disc a grown polygon's corners are rounded with
GROWTH_ERROR = 1.0 - math.cos(math.pi / GROWTH_SAMPLES)  # how far inside the exact grown shape its chords lie, × pad


def grown_polygon(polygon: np.ndarray, pad_m: float) -> np.ndarray:
    """A convex polygon grown by ``pad_m`` (its Minkowski sum with a disc of that radius): the convex hull of its
    vertices each moved by ``pad_m`` in :data:`GROWTH_SAMPLES` directions, counter-clockwise. Its edges lie inside
    the exact grown shape by at most ``pad_m`` × :data:`GROWTH_ERROR` (0.12 % of the pad), so a pose it finds free
    keeps the original polygon that far from every obstacle, up to that. A polygon that is not convex is refused
    (ValueError): the hull of a grown non-convex polygon would fill its notches."""
    from scipy.spatial import ConvexHull

    from planner.maps.clearance import convex_turn

    poly = np.ascontiguousarray(np.asarray(polygon, dtype=np.float64).reshape(-1, 2))
    if not math.isfinite(pad_m) or pad_m < 0:
        raise ValueError(f"the pad must be a finite number ≥ 0, not {pad_m!r}")
    if convex_turn(np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1])) == 0:
        raise ValueError("only a convex footprint can be grown by a pad (this one is not convex)")
    if pad_m == 0:
        return poly.copy()
    angles = np.linspace(0.0, 2.0 * math.pi, GROWTH_SAMPLES, endpoint=False)
    ring = pad_m * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    points = (poly[:, None, :] + ring[None, :, :]).reshape(-1, 2)
    return np.ascontiguousarray(points[ConvexHull(points).vertices])
