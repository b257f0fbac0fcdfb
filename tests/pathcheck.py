"""An independent checker for planned paths, written apart from the planner's own collision code.

It rasterises the real footprint rectangle at every state on the *raw* grid (no distance transform, no
covering circles) and checks the sphere's kinematic constraints between consecutive states.
"""

from __future__ import annotations

import math

import numpy as np

from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile


def footprint_hits(grid: OccupancyGrid, robot: RobotProfile, x: float, y: float, yaw: float) -> bool:
    """True when the footprint rectangle at (x, y, yaw) overlaps a blocked cell or leaves the map."""
    res = grid.resolution_m
    hl, hw = robot.footprint_length_m / 2, robot.footprint_width_m / 2
    c, s = math.cos(yaw), math.sin(yaw)
    corners = np.array([[x + c * a - s * b, y + s * a + c * b] for a in (-hl, hl) for b in (-hw, hw)])
    lo = np.floor((corners.min(axis=0) - grid.origin[:2]) / res).astype(int)
    hi = np.floor((corners.max(axis=0) - grid.origin[:2]) / res).astype(int)
    if lo[0] < 0 or lo[1] < 0 or hi[0] >= grid.width or hi[1] >= grid.height:
        return True
    blocked = grid.blocked()
    for iy in range(lo[1], hi[1] + 1):
        for ix in range(lo[0], hi[0] + 1):
            if not blocked[iy, ix]:
                continue
            # separating-axis test between the cell square and the footprint rectangle
            cx = grid.origin[0] + (ix + 0.5) * res - x
            cy = grid.origin[1] + (iy + 0.5) * res - y
            along, across = c * cx + s * cy, -s * cx + c * cy
            r_cell_along = res / 2 * (abs(c) + abs(s))
            if abs(along) > hl + r_cell_along or abs(across) > hw + r_cell_along:
                continue
            if abs(cx) > res / 2 + hl * abs(c) + hw * abs(s) or abs(cy) > res / 2 + hl * abs(s) + hw * abs(c):
                continue
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
    """Smallest distance (m) from the footprint rectangle at any state to a blocked cell square or the map's
    edge, by brute force over the cells within ``reach_m`` (vertex-to-edge distances of two convex polygons);
    0 where they overlap. Capped at ``reach_m``."""
    res = grid.resolution_m
    hl, hw = robot.footprint_length_m / 2, robot.footprint_width_m / 2
    blocked = grid.blocked()
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) * res
    w, h = grid.size_m
    best = reach_m
    for x, y, yaw in states[:, :3]:
        if footprint_hits(grid, robot, x, y, yaw):
            return 0.0
        c, s = math.cos(yaw), math.sin(yaw)
        body = ((-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw))
        rect = np.array([[x + c * a - s * b, y + s * a + c * b] for a, b in body])
        edge = min((rect[:, 0] - grid.origin[0]).min(), (grid.origin[0] + w - rect[:, 0]).min(),
                   (rect[:, 1] - grid.origin[1]).min(), (grid.origin[1] + h - rect[:, 1]).min())
        best = min(best, edge)
        r = math.hypot(hl, hw) + reach_m
        ix0, iy0 = grid.world_to_cell(x - r, y - r)
        ix1, iy1 = grid.world_to_cell(x + r, y + r)
        ix0, iy0, ix1, iy1 = max(ix0, 0), max(iy0, 0), min(ix1, grid.width - 1), min(iy1, grid.height - 1)
        iy, ix = np.nonzero(blocked[iy0:iy1 + 1, ix0:ix1 + 1])
        if not len(ix):
            continue
        corner = np.column_stack([grid.origin[0] + (ix + ix0) * res, grid.origin[1] + (iy + iy0) * res])
        cells = corner[:, None, :] + sq[None]                      # (n, 4, 2)
        r_a, r_b = rect, np.roll(rect, -1, axis=0)                  # rectangle edges
        c_a, c_b = cells, np.roll(cells, -1, axis=1)                # cell edges
        d1 = _point_segment(cells[:, :, None, :], r_a[None, None], r_b[None, None]).min(axis=(1, 2))
        d2 = _point_segment(rect[None, :, None, :], c_a[:, None], c_b[:, None]).min(axis=(1, 2))
        best = min(best, float(np.minimum(d1, d2).min()))
    return best
