"""The one clearance model: covering circles (paper 001 §4.1), the conservative clearance map, boundary
cells and the exact footprint clearance, each checked against an independent raw-grid computation."""

import itertools
import math

import numpy as np
import pytest

from planner.maps.clearance import (
    CircleFootprint,
    ClearanceMap,
    boundary_cell_centres,
    footprint_clearance,
)
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.pathcheck import footprint_hits
from tests.reconfigcheck import disc_hits

ROBOT = load_robot("zju-60")


def test_circles_cover_the_footprint_rectangle():
    for name in ("zju-60", "zju-80", "daedalus"):
        robot = load_robot(name)
        for n in (1, 2, 3, 5):
            fp = CircleFootprint.for_robot(robot, n)
            rng = np.random.default_rng(n)
            pts = rng.uniform(-0.5, 0.5, (2000, 2)) * [robot.footprint_length_m, robot.footprint_width_m]
            d = np.hypot(pts[:, :1] - fp.offsets_x, pts[:, 1:] - fp.offsets_y).min(axis=1)
            assert np.all(d <= fp.radius_m + 1e-12)


def test_more_circles_cover_less_redundant_area():
    robot = load_robot("zju-60")
    radii = [CircleFootprint.for_robot(robot, n).radius_m for n in (1, 2, 3, 4)]
    assert all(a > b for a, b in itertools.pairwise(radii))


def test_clearance_margin_is_conservative_against_the_raw_grid():
    """Where the circle check says free, the real footprint rectangle touches no blocked cell."""
    rng = np.random.default_rng(11)
    occ = rng.random((120, 120)) < 0.01
    occ[40:60, 50:90] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    robot = load_robot("zju-60")
    fp = CircleFootprint.for_robot(robot)
    clear = ClearanceMap(grid)
    poses = np.column_stack([rng.uniform(0, 6, 3000), rng.uniform(0, 6, 3000), rng.uniform(-3.2, 3.2, 3000)])
    margins = clear.pose_margin(fp, poses)
    free = poses[margins >= 0]
    assert len(free) > 20
    for x, y, yaw in free:
        assert not footprint_hits(grid, robot, x, y, yaw)
    exact = clear.exact_pose_margin(fp, poses)
    assert np.all(exact[np.isfinite(margins)] >= margins[np.isfinite(margins)] - 1e-9)


def test_leaving_the_map_is_a_collision():
    grid = OccupancyGrid.from_occupied(np.zeros((40, 40), bool), 0.1)
    fp = CircleFootprint.for_robot(load_robot())
    clear = ClearanceMap(grid)
    assert clear.pose_margin(fp, np.array([[2.0, 2.0, 0.0]]))[0] > 0
    assert clear.pose_margin(fp, np.array([[0.2, 2.0, 0.0]]))[0] < 0
    assert clear.pose_margin(fp, np.array([[-1.0, 2.0, math.pi]]))[0] == -math.inf


def test_footprint_clearance_against_a_wall() -> None:
    occ = np.zeros((80, 80), dtype=bool)
    occ[:, 60:] = True  # wall from x = 3.0 m
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    half_l, half_w = ROBOT.footprint_length_m / 2, ROBOT.footprint_width_m / 2
    assert footprint_clearance(grid, ROBOT, np.array([[2.0, 2.0, 0.0]])) == pytest.approx(1.0 - half_l)
    assert footprint_clearance(grid, ROBOT, np.array([[2.0, 2.0, math.pi / 2]])) == pytest.approx(1.0 - half_w)
    diag = math.hypot(half_l, half_w)
    yaw = math.atan2(half_w, half_l)  # a corner points straight at the wall
    assert footprint_clearance(grid, ROBOT, np.array([[2.0, 2.0, -yaw]])) == pytest.approx(1.0 - diag)
    assert footprint_clearance(grid, ROBOT, np.array([[2.8, 2.0, 0.0]])) == 0.0
    # the map's edge counts as an obstacle (y = 0 is the bottom edge)
    assert footprint_clearance(grid, ROBOT, np.array([[1.0, 0.5, 0.0]])) == pytest.approx(0.5 - half_w)


def _boxes(boxes: list[tuple[float, float, float, float]]) -> OccupancyGrid:
    """A 20 m × 16 m map at 0.1 m with the given (x0, y0, x1, y1) boxes blocked."""
    occ = np.zeros((160, 200), dtype=bool)
    for x0, y0, x1, y1 in boxes:
        occ[int(y0 / 0.1):int(y1 / 0.1), int(x0 / 0.1):int(x1 / 0.1)] = True
    return OccupancyGrid.from_occupied(occ, 0.1)


def test_clearance_map_is_a_lower_bound_on_the_raw_grid_distance():
    grid = _boxes([(7.0, 7.0, 8.0, 8.0), (4.0, 9.0, 4.5, 13.0)])
    rng = np.random.default_rng(7)
    xs, ys = rng.uniform(0.5, 19.5, 400), rng.uniform(0.5, 15.5, 400)
    clear = ClearanceMap(grid).at(xs, ys)
    assert np.isfinite(clear).all()
    for x, y, c in zip(xs, ys, clear, strict=True):
        if c > 0:
            assert not disc_hits(grid, x, y, c)


def test_boundary_cells_are_the_blocked_cells_next_to_free_space():
    grid = _boxes([(7.0, 7.0, 8.0, 8.0)])  # a 10 × 10 cell block: 36 boundary cells, 64 inside
    centres = boundary_cell_centres(grid)
    assert len(centres) == 36
    assert np.all((centres >= 7.0) & (centres <= 8.0))
    with_edge = boundary_cell_centres(grid, edge_blocked=True)
    assert len(with_edge) == 36 + 2 * (200 + 160) + 4  # plus the ring just outside the map
