"""A brute-force footprint-polygon checker for tests, sharing no code with lab/planning/referee.py.

It clips the placed polygon against every blocked cell square near it (Sutherland–Hodgman) and calls a pose
colliding when some clipped area is positive or a vertex leaves the map; clearances are vertex-to-edge
distances over every blocked cell, in numpy. Slow, simple, for small grids.
"""

from __future__ import annotations

import math

import numpy as np

from planner.occupancy import OccupancyGrid


def placed(poly: np.ndarray, pose: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.column_stack([pose[0] + c * poly[:, 0] - s * poly[:, 1], pose[1] + s * poly[:, 0] + c * poly[:, 1]])


def clip_area(pts: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> float:
    """Area of the polygon clipped to the box (Sutherland–Hodgman against the four half-planes)."""
    poly = [tuple(p) for p in pts]
    for axis, bound, keep_above in ((0, x0, True), (0, x1, False), (1, y0, True), (1, y1, False)):
        def inside(p: tuple[float, float], axis: int = axis, bound: float = bound, above: bool = keep_above) -> bool:
            return p[axis] >= bound if above else p[axis] <= bound

        out: list[tuple[float, float]] = []
        for i, cur in enumerate(poly):
            prev = poly[i - 1]
            if inside(cur) != inside(prev):
                t = (bound - prev[axis]) / (cur[axis] - prev[axis])
                out.append((prev[0] + t * (cur[0] - prev[0]), prev[1] + t * (cur[1] - prev[1])))
            if inside(cur):
                out.append(cur)
        poly = out
        if not poly:
            return 0.0
    a = np.array(poly)
    return 0.5 * abs(float(np.sum(a[:, 0] * np.roll(a[:, 1], -1) - np.roll(a[:, 0], -1) * a[:, 1])))


def brute_collides(grid: OccupancyGrid, poly: np.ndarray, pose: np.ndarray, allow_unknown: bool) -> bool:
    pts = placed(poly, pose)
    ox, oy = grid.origin[:2]
    w, h = grid.size_m
    if (pts[:, 0] < ox).any() or (pts[:, 0] > ox + w).any() or (pts[:, 1] < oy).any() or (pts[:, 1] > oy + h).any():
        return True
    res = grid.resolution_m
    iys, ixs = np.nonzero(grid.blocked(allow_unknown))
    near = np.hypot(ox + (ixs + 0.5) * res - pose[0], oy + (iys + 0.5) * res - pose[1]) <= 1.0
    for iy, ix in zip(iys[near], ixs[near], strict=True):  # every footprint tested lies within 0.6 m of its centre
        if clip_area(pts, ox + ix * res, oy + iy * res, ox + (ix + 1) * res, oy + (iy + 1) * res) > 1e-14:
            return True
    return False


def seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((p - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


def brute_clearance(grid: OccupancyGrid, poly: np.ndarray, pose: np.ndarray, cap: float) -> float:
    if brute_collides(grid, poly, pose, False):
        return 0.0
    pts = placed(poly, pose)
    ox, oy = grid.origin[:2]
    w, h = grid.size_m
    best = min(cap, (pts[:, 0] - ox).min(), (ox + w - pts[:, 0]).min(), (pts[:, 1] - oy).min(),
               (oy + h - pts[:, 1]).min())
    res = grid.resolution_m
    iy, ix = np.nonzero(grid.blocked())
    lo = np.column_stack([ox + ix * res, oy + iy * res])                      # (m, 2) lower-left corners
    hi = lo + res
    gap = np.maximum(np.maximum(lo[None] - pts[:, None], pts[:, None] - hi[None]), 0.0)  # (n, m, 2)
    best = min(best, float(np.linalg.norm(gap, axis=-1).min()))
    corners = np.stack([lo, np.column_stack([hi[:, 0], lo[:, 1]]), hi, np.column_stack([lo[:, 0], hi[:, 1]])], 1)
    a, b = pts, np.roll(pts, -1, axis=0)
    d = seg_dist(corners[:, :, None, :], a[None, None], b[None, None])
    return min(best, float(d.min()))
