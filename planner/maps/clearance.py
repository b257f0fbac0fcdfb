"""The one clearance model: how far every point of a map is from the nearest obstacle, and whether a
robot's footprint fits there. Every wing asks it: the Hybrid A* (covering circles, paper 001 §4.1,
Fig. 6), the MPC tracker (obstacle circles on boundary cells, paper 001 eq. 15f), the closed-loop
simulation (exact footprint clearance), the Spherobot swept-disc check and the map generator.

Three-circle footprint collision checking (paper 001 §4.1, Fig. 6):

The robot's footprint (a ``footprint_length_m`` × ``footprint_width_m`` rectangle centred on the sphere,
length along the heading) is covered by N circles (default 3) of radius r_c placed along its longer
axis; their union covers the rectangle. Obstacles are "inflated" by r_c through a Euclidean distance
transform, so a pose is free when every circle centre has clearance ≥ r_c: O(N) lookups per pose.

Clearance is conservative: the distance transform measures cell centre to cell centre (d), and a point
anywhere in a cell is at least d − √2·res from any point of the nearest blocked cell, so that is what
is stored. Cells outside the map count as blocked (the robot must stay on the map).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.ndimage import distance_transform_edt
from scipy.spatial import cKDTree

from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile


@dataclass(frozen=True)
class CircleFootprint:
    """N covering circles in the body frame (x forward, y left), metres."""

    offsets_x: np.ndarray
    offsets_y: np.ndarray
    radius_m: float

    @classmethod
    def for_robot(cls, robot: RobotProfile, n_circles: int = 3) -> CircleFootprint:
        """Cover the footprint rectangle with ``n_circles`` equal circles along its longer axis."""
        if n_circles < 1:
            raise ValueError("n_circles must be >= 1")
        length, width = robot.footprint_length_m, robot.footprint_width_m
        long_axis, short_axis = max(length, width), min(length, width)
        seg = long_axis / n_circles
        centres = (np.arange(n_circles) + 0.5) * seg - long_axis / 2.0
        r_c = math.hypot(seg / 2.0, short_axis / 2.0)
        zeros = np.zeros(n_circles)
        if length >= width:
            return cls(centres, zeros, r_c)
        return cls(zeros, centres, r_c)

    def centres(self, x: float, y: float, yaw: float) -> np.ndarray:
        """World positions (N, 2) of the circle centres at pose (x, y, yaw)."""
        c, s = math.cos(yaw), math.sin(yaw)
        return np.stack(
            [x + c * self.offsets_x - s * self.offsets_y, y + s * self.offsets_x + c * self.offsets_y], axis=1
        )


def centre_distance(grid: OccupancyGrid, allow_unknown: bool = False) -> np.ndarray:
    """Distance (m, shape (height, width)) from each cell centre to the nearest blocked cell centre, the
    ring of cells just outside the map counting as blocked (Euclidean distance transform)."""
    padded = np.pad(grid.blocked(allow_unknown), 1, constant_values=True)
    return np.asarray(distance_transform_edt(~padded)[1:-1, 1:-1] * grid.resolution_m, dtype=np.float64)


def boundary_cell_centres(grid: OccupancyGrid, allow_unknown: bool = False, edge_blocked: bool = False) -> np.ndarray:
    """World centres (n, 2) of the blocked cells that touch a free cell (4-neighbourhood): the only cells
    a body coming from free space can reach first. With ``edge_blocked`` the ring of cells just outside the
    map counts as blocked too."""
    blocked = grid.blocked(allow_unknown)
    res = grid.resolution_m
    ox, oy = float(grid.origin[0]), float(grid.origin[1])
    if edge_blocked:
        blocked = np.pad(blocked, 1, constant_values=True)
        ox, oy = ox - res, oy - res
    pad = np.pad(blocked, 1, constant_values=False)
    interior = pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:]
    iy, ix = np.nonzero(blocked & ~interior)
    return np.stack([ox + (ix + 0.5) * res, oy + (iy + 0.5) * res], axis=1)


class ClearanceMap:
    """Conservative clearance (m) of every cell to the nearest blocked cell, for O(1) pose checks."""

    def __init__(self, grid: OccupancyGrid, allow_unknown: bool = False) -> None:
        self.grid = grid
        self.blocked = grid.blocked(allow_unknown)
        self.clearance = centre_distance(grid, allow_unknown) - math.sqrt(2.0) * grid.resolution_m
        self.origin_x = float(grid.origin[0])
        self.origin_y = float(grid.origin[1])
        self.resolution_m = float(grid.resolution_m)
        self._tree: cKDTree | None = None
        self._blocked_centres = np.zeros((0, 2))

    def at(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Clearance at world points (vectorised); −inf outside the map."""
        return _clearance_at(self.clearance, self.origin_x, self.origin_y, self.resolution_m,
                             np.asarray(xs, float).ravel(), np.asarray(ys, float).ravel())

    def pose_margin(self, footprint: CircleFootprint, poses: np.ndarray) -> np.ndarray:
        """Per pose (rows x, y, yaw): min over circles of clearance − r_c. Free where ≥ 0."""
        poses = np.atleast_2d(np.asarray(poses, float))
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        cx = poses[:, 0:1] + c * footprint.offsets_x - s * footprint.offsets_y
        cy = poses[:, 1:2] + s * footprint.offsets_x + c * footprint.offsets_y
        clear = self.at(cx, cy).reshape(cx.shape)
        return clear.min(axis=1) - footprint.radius_m

    def exact_pose_margin(self, footprint: CircleFootprint, poses: np.ndarray) -> np.ndarray:
        """Per pose: min over circles of the *exact* distance to the nearest blocked cell square − r_c.

        Independent of the distance transform (used for the final fine re-check and the reported
        clearance): blocked cells are squares of side ``resolution_m`` (the nearest square is among the
        8 nearest cell centres); distances are capped at r_c + 1 m; leaving the map counts as −inf.
        """
        poses = np.atleast_2d(np.asarray(poses, float))
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        cx = (poses[:, 0:1] + c * footprint.offsets_x - s * footprint.offsets_y).ravel()
        cy = (poses[:, 1:2] + s * footprint.offsets_x + c * footprint.offsets_y).ravel()
        res = self.resolution_m
        reach = footprint.radius_m + 1.0
        dist = np.full(cx.size, reach)
        if self._tree is None:
            iy, ix = np.nonzero(self.blocked)
            self._blocked_centres = np.column_stack(
                [self.origin_x + (ix + 0.5) * res, self.origin_y + (iy + 0.5) * res]
            )
            self._tree = cKDTree(self._blocked_centres) if len(ix) else None
        if self._tree is not None:
            pts = np.column_stack([cx, cy])
            k = min(8, len(self._blocked_centres))
            _, idx = self._tree.query(pts, k=k, distance_upper_bound=reach)
            idx = idx.reshape(len(pts), k)
            valid = idx < len(self._blocked_centres)
            centres = self._blocked_centres[np.where(valid, idx, 0)]
            gap = np.maximum(np.abs(centres - pts[:, None, :]) - res / 2, 0.0)
            exact = np.where(valid, np.hypot(gap[..., 0], gap[..., 1]), reach)
            dist = np.minimum(dist, exact.min(axis=1))
        w, h = self.grid.size_m
        ex = np.minimum.reduce([cx - self.origin_x, self.origin_x + w - cx, cy - self.origin_y, self.origin_y + h - cy])
        dist = np.where(ex < 0, -np.inf, np.minimum(dist, ex))
        return dist.reshape(poses.shape[0], -1).min(axis=1) - footprint.radius_m


@njit(cache=True)
def _clearance_at(clear: np.ndarray, ox: float, oy: float, res: float, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    out = np.empty(xs.size)
    h, w = clear.shape
    for i in range(xs.size):
        ix = int(math.floor((xs[i] - ox) / res))
        iy = int(math.floor((ys[i] - oy) / res))
        out[i] = clear[iy, ix] if 0 <= ix < w and 0 <= iy < h else -math.inf
    return out


@njit(cache=True)
def pose_margin_nb(
    clear: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, yaw: float,
    offx: np.ndarray, offy: np.ndarray, r_c: float,
) -> float:
    """Min over circles of (clearance − r_c) at one pose; −inf when a circle leaves the map."""
    c = math.cos(yaw)
    s = math.sin(yaw)
    h, w = clear.shape
    best = math.inf
    for k in range(offx.size):
        px = x + c * offx[k] - s * offy[k]
        py = y + s * offx[k] + c * offy[k]
        ix = int(math.floor((px - ox) / res))
        iy = int(math.floor((py - oy) / res))
        if ix < 0 or iy < 0 or ix >= w or iy >= h:
            return -math.inf
        m = clear[iy, ix] - r_c
        if m < best:
            best = m
    return best


def footprint_clearance(grid: OccupancyGrid, robot: RobotProfile, poses: np.ndarray) -> float:
    """Smallest distance (m) between the footprint rectangle at any of ``poses`` (m, 3: x, y, yaw) and a
    blocked cell (occupied or unknown) of the raw map; cells outside the map count as blocked. 0 when
    they overlap. Exact for rectangle vs. square cells (closest features are a vertex and a side)."""
    res = grid.resolution_m
    blocked = grid.blocked()
    centres = boundary_cell_centres(grid, edge_blocked=True)
    tree = cKDTree(centres)
    hl, hw = robot.footprint_length_m / 2, robot.footprint_width_m / 2
    half_diag = math.hypot(hl, hw)
    sq = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * res / 2
    rect = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
    d0, _ = tree.query(poses[:, :2])
    best = np.inf
    for k in np.argsort(d0):
        if d0[k] - half_diag - res > best:
            break
        x, y, th = poses[k]
        ixc, iyc = grid.world_to_cell(x, y)
        if not (0 <= ixc < grid.width and 0 <= iyc < grid.height) or blocked[iyc, ixc]:
            return 0.0
        cand = centres[tree.query_ball_point((x, y), d0[k] + half_diag + res)]
        c, s = math.cos(th), math.sin(th)
        # square corners in the body frame → distance to the rectangle box
        corners = cand[:, None, :] + sq[None]
        rel = corners - (x, y)
        bx = rel[..., 0] * c + rel[..., 1] * s
        by = -rel[..., 0] * s + rel[..., 1] * c
        d_sq = np.hypot(np.maximum(np.abs(bx) - hl, 0), np.maximum(np.abs(by) - hw, 0)).min()
        # rectangle corners in the world frame → distance to each square box
        wc = np.stack([x + rect[:, 0] * c - rect[:, 1] * s, y + rect[:, 0] * s + rect[:, 1] * c], axis=1)
        rr = np.abs(wc[None] - cand[:, None, :]) - res / 2
        d_rc = np.hypot(np.maximum(rr[..., 0], 0), np.maximum(rr[..., 1], 0)).min()
        best = min(best, float(d_sq), float(d_rc))
        if best <= 0:
            return 0.0
    return float(best)
