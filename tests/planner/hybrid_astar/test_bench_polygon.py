"""The benchmark's exact polygon checker against a brute-force rasterisation on random poses.

The brute force here shares no code with :mod:`planner.hybrid_astar.bench_polygon`: it clips the placed
polygon against every blocked cell square of the whole grid (Sutherland–Hodgman) and calls a pose colliding
when some clipped area is positive or a vertex leaves the map; clearances are vertex-to-edge distances
over every blocked cell, in numpy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.hybrid_astar.bench_polygon import PolygonChecker
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot

ZJU = load_robot("zju-60").footprint_polygon
# a non-convex footprint (an arrow head), to show the checks do not assume convexity
ARROW = np.array([[0.45, 0.0], [-0.3, 0.35], [-0.1, 0.0], [-0.3, -0.35]])


def _grid(seed: int) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    data = np.zeros((90, 110), dtype=np.int8)
    data[rng.random(data.shape) < 0.002] = 100  # scattered single cells
    data[rng.random(data.shape) < 0.001] = -1
    data[30:33, 5:60] = 100  # a wall and a block, so that many poses graze something
    data[55:68, 65:72] = -1
    return OccupancyGrid(data=data, resolution_m=0.05, origin=(-1.3, 0.7, 0.0), name="random")


def _placed(poly: np.ndarray, pose: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.column_stack([pose[0] + c * poly[:, 0] - s * poly[:, 1], pose[1] + s * poly[:, 0] + c * poly[:, 1]])


def _clip_area(pts: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> float:
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


def _brute_collides(grid: OccupancyGrid, poly: np.ndarray, pose: np.ndarray, allow_unknown: bool) -> bool:
    pts = _placed(poly, pose)
    ox, oy = grid.origin[:2]
    w, h = grid.size_m
    if (pts[:, 0] < ox).any() or (pts[:, 0] > ox + w).any() or (pts[:, 1] < oy).any() or (pts[:, 1] > oy + h).any():
        return True
    res = grid.resolution_m
    for iy, ix in zip(*np.nonzero(grid.blocked(allow_unknown)), strict=True):
        if math.hypot(ox + (ix + 0.5) * res - pose[0], oy + (iy + 0.5) * res - pose[1]) > 1.0:
            continue  # every footprint tested here lies within 0.6 m of its centre
        if _clip_area(pts, ox + ix * res, oy + iy * res, ox + (ix + 1) * res, oy + (iy + 1) * res) > 1e-14:
            return True
    return False


def _seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((p - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


def _brute_clearance(grid: OccupancyGrid, poly: np.ndarray, pose: np.ndarray, cap: float) -> float:
    if _brute_collides(grid, poly, pose, False):
        return 0.0
    pts = _placed(poly, pose)
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
    d = _seg_dist(corners[:, :, None, :], a[None, None], b[None, None])
    return min(best, float(d.min()))


def _random_poses(grid: OccupancyGrid, rng: np.random.Generator, n: int) -> np.ndarray:
    ox, oy = grid.origin[:2]
    w, h = grid.size_m
    return np.column_stack([rng.uniform(ox, ox + w, n), rng.uniform(oy, oy + h, n), rng.uniform(-np.pi, np.pi, n)])


@pytest.mark.parametrize(("poly", "allow_unknown"), [(ZJU, False), (ARROW, False), (ZJU, True)])
def test_collision_matches_brute_force(poly: np.ndarray, allow_unknown: bool) -> None:
    grid = _grid(1)
    rng = np.random.default_rng(7)
    checker = PolygonChecker(poly.copy(), grid.blocked(allow_unknown), grid.origin[:2], grid.resolution_m)
    poses = _random_poses(grid, rng, 250)
    expected = np.array([_brute_collides(grid, poly, p, allow_unknown) for p in poses])
    got = checker.collides_many(poses)
    assert 30 < expected.sum() < 220, "the sample must hold both free and colliding poses"
    np.testing.assert_array_equal(got, expected)
    assert [checker.collides(*p) for p in poses[:40]] == expected[:40].tolist()


def test_unknown_blocks_unless_allowed_and_leaving_the_map_collides() -> None:
    data = np.zeros((40, 40), dtype=np.int8)
    data[20, 20] = -1
    grid = OccupancyGrid(data=data, resolution_m=0.05)
    robot = load_robot("zju-60")
    strict, lax = PolygonChecker.for_robot(grid, robot), PolygonChecker.for_robot(grid, robot, allow_unknown=True)
    assert strict.collides(1.025, 1.025, 0.3) and not lax.collides(1.025, 1.025, 0.3)
    # 0.32 m from the centre to the padded polygon's front; the map edge at x = 2.0
    assert not lax.collides(2.0 - 0.321, 0.5, 0.0) and lax.collides(2.0 - 0.319, 0.5, 0.0)
    assert lax.clearances(np.array([[2.0 - 0.42, 0.5, 0.0]]))[0] == pytest.approx(0.1, abs=1e-9)


@pytest.mark.parametrize("poly", [ZJU, ARROW])
def test_clearance_matches_brute_force(poly: np.ndarray) -> None:
    grid = _grid(2)
    rng = np.random.default_rng(3)
    checker = PolygonChecker(poly.copy(), grid.blocked(), grid.origin[:2], grid.resolution_m)
    poses = _random_poses(grid, rng, 120)
    expected = np.array([_brute_clearance(grid, poly, p, 0.5) for p in poses])
    got = checker.clearances(poses, reach_m=0.5)
    assert (expected > 0).sum() > 20 and (expected == 0).sum() > 10
    np.testing.assert_allclose(got, expected, atol=1e-9)
    assert checker.min_clearance(poses, 0.5) == pytest.approx(expected.min())


def test_inradius_and_circumradius_of_the_zju_polygon() -> None:
    grid = _grid(0)
    checker = PolygonChecker.for_robot(grid, load_robot("zju-60"))
    assert checker.inradius_m == pytest.approx(0.32)  # the padded 16-gon's front edge: 0.30 / cos(π/16)·… + 0.02
    assert checker.circumradius_m == pytest.approx(float(np.hypot(ZJU[:, 0], ZJU[:, 1]).max()))
