"""Three-circle footprint coverage and the conservative clearance map (paper 001 §4.1)."""

import itertools
import math

import numpy as np

from planner.collision import CircleFootprint, ClearanceMap
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.pathcheck import footprint_hits


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
