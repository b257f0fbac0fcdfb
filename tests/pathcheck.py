"""An independent checker for planned paths, written apart from the planner's own collision code.

It tests the robot's padded footprint polygon at every state against the cell squares of the *raw* grid
(matplotlib's path geometry; no distance transform, no covering circles) and checks the sphere's
kinematic constraints between consecutive states.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.path import Path
from matplotlib.transforms import Bbox

from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile


def _world_polygon(robot: RobotProfile, x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    body = robot.footprint_polygon
    return np.column_stack([x + c * body[:, 0] - s * body[:, 1], y + s * body[:, 0] + c * body[:, 1]])


def _cells_near(grid: OccupancyGrid, poly: np.ndarray, reach_m: float) -> np.ndarray:
    """Lower-left corners (n, 2) of the blocked cells whose square lies within ``reach_m`` of the polygon's box."""
    res = grid.resolution_m
    lo = np.floor((poly.min(axis=0) - reach_m - grid.origin[:2]) / res).astype(int)
    hi = np.floor((poly.max(axis=0) + reach_m - grid.origin[:2]) / res).astype(int)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, [grid.width - 1, grid.height - 1])
    iy, ix = np.nonzero(grid.blocked()[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1])
    return np.column_stack([grid.origin[0] + (ix + lo[0]) * res, grid.origin[1] + (iy + lo[1]) * res])


def footprint_hits(grid: OccupancyGrid, robot: RobotProfile, x: float, y: float, yaw: float) -> bool:
    """True when the padded footprint polygon at (x, y, yaw) overlaps a blocked cell or leaves the map
    (matplotlib's path geometry: a cell square meets the polygon when either contains a point of the other
    or their outlines cross)."""
    poly = _world_polygon(robot, x, y, yaw)
    w, h = grid.size_m
    if (poly[:, 0].min() < grid.origin[0] or poly[:, 1].min() < grid.origin[1]
            or poly[:, 0].max() >= grid.origin[0] + w or poly[:, 1].max() >= grid.origin[1] + h):
        return True
    res = grid.resolution_m
    outline = Path(np.vstack([poly, poly[:1]]), closed=True)
    for cx, cy in _cells_near(grid, poly, 0.0):
        if outline.intersects_bbox(Bbox([[cx, cy], [cx + res, cy + res]]), filled=True):
            return True
    return False


def check_path(
    grid: OccupancyGrid, robot: RobotProfile, states: np.ndarray, start: tuple[float, float, float],
    goal: tuple[float, float, float], tol_xy: float = 0.1, tol_yaw: float = math.radians(5),
    max_spacing: float = 0.05,
) -> list[str]:
    """Return a list of violated properties (empty = the path is valid)."""
    problems: list[str] = []
    x, y, yaw, roll, s = states[:, 0], states[:, 1], states[:, 2], states[:, 3], states[:, 6]
    if math.hypot(x[0] - start[0], y[0] - start[1]) > 1e-6:
        problems.append("path does not begin at the start")
    if math.hypot(x[-1] - goal[0], y[-1] - goal[1]) > tol_xy:
        problems.append(f"path ends {math.hypot(x[-1] - goal[0], y[-1] - goal[1]):.3f} m from the goal")
    if abs(math.remainder(yaw[-1] - goal[2], 2 * math.pi)) > tol_yaw:
        problems.append("path ends with the wrong heading")
    if abs(roll[0]) > 1e-9 or abs(roll[-1]) > 1e-9:
        problems.append("the sphere must start and end upright (roll 0)")
    step = np.hypot(np.diff(x), np.diff(y))
    if step.max(initial=0) > max_spacing + 1e-9:
        problems.append(f"states are {step.max():.3f} m apart (> {max_spacing} m)")
    if np.any(np.abs(roll) > robot.max_roll_rad + 1e-9):
        problems.append("roll exceeds the profile's maximum")
    d_yaw = np.abs(np.remainder(np.diff(yaw) + np.pi, 2 * np.pi) - np.pi)
    d_s = np.diff(s)
    kmax = robot.max_curvature
    moving = d_s > 1e-9
    if np.any(d_yaw[moving] > kmax * d_s[moving] * (1 + 1e-3) + 1e-9):  # chord vs arc: (κ·ds)²/24
        problems.append("heading changes faster than tan(max roll) / r allows")
    # sideways motion only from roll changes: lateral displacement = r·Δroll (+ the arc's own sagitta)
    heading = yaw[:-1]
    lateral = -np.sin(heading) * np.diff(x) + np.cos(heading) * np.diff(y)
    expected = robot.radius_m * np.diff(roll)
    sagitta = kmax * step**2
    if np.any(np.abs(lateral - expected) > sagitta + 1e-6):
        problems.append("the centre moves sideways without a roll change")
    for i in range(len(states)):
        if footprint_hits(grid, robot, x[i], y[i], yaw[i]):
            problems.append(f"footprint overlaps an obstacle at state {i} ({x[i]:.2f}, {y[i]:.2f})")
            break
    return problems


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points p (..., 2) to the segments a→b (..., 2)."""
    ab = b - a
    t = np.clip(((p - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
    return np.hypot(*np.moveaxis(a + t[..., None] * ab - p, -1, 0))


def footprint_distance(grid: OccupancyGrid, robot: RobotProfile, states: np.ndarray, reach_m: float = 1.5) -> float:
    """Smallest distance (m) from the padded footprint polygon at any state to a blocked cell square or the
    map's edge, by brute force over the cells within ``reach_m`` (vertex-to-edge distances of the two
    polygons); 0 where they overlap. Capped at ``reach_m``."""
    res = grid.resolution_m
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) * res
    w, h = grid.size_m
    best = reach_m
    for x, y, yaw in states[:, :3]:
        if footprint_hits(grid, robot, x, y, yaw):
            return 0.0
        poly = _world_polygon(robot, x, y, yaw)
        edge = min((poly[:, 0] - grid.origin[0]).min(), (grid.origin[0] + w - poly[:, 0]).min(),
                   (poly[:, 1] - grid.origin[1]).min(), (grid.origin[1] + h - poly[:, 1]).min())
        best = min(best, edge)
        corner = _cells_near(grid, poly, reach_m)
        if not len(corner):
            continue
        cells = corner[:, None, :] + sq[None]                      # (n, 4, 2)
        p_a, p_b = poly, np.roll(poly, -1, axis=0)                  # polygon edges
        c_a, c_b = cells, np.roll(cells, -1, axis=1)                # cell edges
        d1 = _point_segment(cells[:, :, None, :], p_a[None, None], p_b[None, None]).min(axis=(1, 2))
        d2 = _point_segment(poly[None, :, None, :], c_a[:, None], c_b[:, None]).min(axis=(1, 2))
        best = min(best, float(np.minimum(d1, d2).min()))
    return best
