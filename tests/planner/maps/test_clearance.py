"""The one clearance model: covering circles (paper 001 §4.1), the conservative clearance map, boundary
cells and the exact footprint clearance, each checked against an independent raw-grid computation."""

import itertools
import math
import types

import numpy as np
import pytest
from matplotlib.path import Path
from numba import njit

from planner.maps.clearance import (
    LEAST_SEED_M,
    CircleFootprint,
    ClearanceMap,
    _point_in_polygon,
    _segment_meets_box,
    boundary_cell_centres,
    convex_turn,
    least_footprint_distance,
)
from planner.maps.clearance import footprint_hits as footprint_hits_compiled
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile, load_robot, profile_from_dict
from tests.pathcheck import footprint_distance, footprint_hits
from tests.reconfigcheck import disc_hits


def _box_robot(half_length: float, half_width: float, padding: float = 0.0) -> RobotProfile:
    data = {"name": "box", "radius_m": 0.3, "max_roll_deg": 15, "max_roll_rate_deg_s": 30, "roll_time_constant_s": 0.1,
            "max_speed_m_s": 0.5, "max_accel_m_s2": 0.5, "footprint_padding_m": padding,
            "footprint": [[half_length, half_width], [-half_length, half_width], [-half_length, -half_width],
                          [half_length, -half_width]]}
    return profile_from_dict(data)


def _inside(poly: np.ndarray, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    pts = rng.uniform(lo, hi, (n, 2))
    return pts[Path(poly).contains_points(pts)]


@pytest.mark.parametrize("robot", [load_robot("zju-60"), load_robot("zju-80"), load_robot("daedalus"),
                                   _box_robot(0.6, 0.2, 0.02)], ids=["zju-60", "zju-80", "daedalus", "box"])
def test_circles_cover_the_padded_polygon(robot: RobotProfile) -> None:
    poly = robot.footprint_polygon
    pts = np.vstack([_inside(poly, 4000, 1), poly])
    for fp in [CircleFootprint.covering(poly, n) for n in (1, 2, 3, 5)] + [CircleFootprint.for_robot(robot)]:
        d = np.hypot(pts[:, :1] - fp.offsets_x, pts[:, 1:] - fp.offsets_y).min(axis=1)
        assert np.all(d <= fp.radius_m)


def test_the_covering_overshooting_least_is_chosen():
    # a round sphere is best covered by one circle, a long body by several along its length
    assert len(CircleFootprint.for_robot(load_robot("zju-60")).offsets_x) == 1
    long_body = _box_robot(0.6, 0.2)
    fp = CircleFootprint.for_robot(long_body)
    assert len(fp.offsets_x) == 3 and np.all(fp.offsets_y == 0)
    assert fp.excess(long_body.footprint_polygon) < CircleFootprint.covering(long_body.footprint_polygon, 1).excess(
        long_body.footprint_polygon)
    radii = [CircleFootprint.covering(long_body.footprint_polygon, n).radius_m for n in (1, 2, 3, 4)]
    assert all(a > b for a, b in itertools.pairwise(radii))


def _random_world(seed: int) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    occ = rng.random((120, 120)) < 0.01
    occ[40:60, 50:90] = True
    return OccupancyGrid.from_occupied(occ, 0.05)


@pytest.mark.parametrize("robot", [load_robot("zju-60"), _box_robot(0.6, 0.2, 0.02)], ids=["zju-60", "box"])
def test_two_tier_check_agrees_with_an_independent_polygon_test(robot: RobotProfile) -> None:
    """Circles first, the polygon where they touch: free exactly where the real padded polygon touches nothing."""
    grid = _random_world(11)
    rng = np.random.default_rng(12)
    fp = CircleFootprint.for_robot(robot)
    clear = ClearanceMap(grid)
    poses = np.column_stack([rng.uniform(0, 6, 1500), rng.uniform(0, 6, 1500), rng.uniform(-3.2, 3.2, 1500)])
    margins = clear.footprint_margins(fp, robot.footprint_polygon, poses)
    circles = clear.circle_margins(fp, poses)
    assert np.all(margins[circles >= 0] == circles[circles >= 0])  # the cheap tier answers where it can
    hits = np.array([footprint_hits(grid, robot, x, y, yaw) for x, y, yaw in poses])
    assert 50 < hits.sum() < len(poses) - 50
    assert np.array_equal(margins < 0, hits)
    # the polygon fits in places the circles alone would refuse
    assert np.sum((circles < 0) & ~hits) > 10


def test_exact_footprint_distance_agrees_with_brute_force():
    grid = _random_world(3)
    robot = _box_robot(0.6, 0.2, 0.02)
    rng = np.random.default_rng(4)
    clear = ClearanceMap(grid)
    poses = np.column_stack([rng.uniform(0.5, 5.5, 60), rng.uniform(0.5, 5.5, 60), rng.uniform(-3.2, 3.2, 60)])
    fast = clear.footprint_distances(robot.footprint_polygon, poses, reach_m=1.0)
    for pose, d in zip(poses, fast, strict=True):
        assert d == pytest.approx(footprint_distance(grid, robot, pose[None], reach_m=1.0), abs=1e-9)
    fp = CircleFootprint.for_robot(robot)
    lower = clear.circle_margins(fp, poses)
    assert np.all(lower <= fast + 1e-9)  # the circles' margin is a lower bound of the true distance
    assert clear.least_footprint_distance(robot.footprint_polygon, poses, lower) == pytest.approx(fast.min(), abs=1e-12)
    # every pose above meets a cell (1 % of the cells are blocked and the box is 1.24 m long), so its distance is 0:
    # a bound 0.5 m low changes nothing there
    loose = fast - 0.5
    assert loose.min() + LEAST_SEED_M < fast.min()
    assert clear.least_footprint_distance(robot.footprint_polygon, poses, loose) == pytest.approx(fast.min(), abs=1e-12)
    # free poses, on the same map with only its block: distances above 0 against the brute force, and a bound 0.5 m
    # low, under which the first pose's measure within bound + LEAST_SEED_M falls short: it is measured again with
    # the full reach (the least is exact, not that short measure's cap)
    occ = np.zeros((120, 120), bool)
    occ[40:60, 50:90] = True
    sparse = OccupancyGrid.from_occupied(occ, 0.05)
    open_clear = ClearanceMap(sparse)
    d_open = open_clear.footprint_distances(robot.footprint_polygon, poses, reach_m=1.0)
    free = poses[d_open > 0.25]
    assert len(free) >= 10
    d_free = d_open[d_open > 0.25]
    for pose, d in zip(free, d_free, strict=True):
        assert d == pytest.approx(footprint_distance(sparse, robot, pose[None], reach_m=1.0), abs=1e-9)
    assert open_clear.least_footprint_distance(robot.footprint_polygon, free, d_free - 0.5) == pytest.approx(
        d_free.min(), abs=1e-12)


def test_least_footprint_distance_keeps_a_reach_under_its_first_measure() -> None:
    """A reach under LEAST_SEED_M and a lower bound below 0: the least is capped at the reach, never the first pose's
    measure within bound + LEAST_SEED_M (0.15 m here)."""
    robot = _box_robot(0.3, 0.35)
    occ = np.zeros((80, 80), dtype=bool)
    occ[:, 60:] = True  # a wall from x = 3.0 m; the box's front (0.3 m ahead) is 0.15 m from it at x = 2.55
    clear = ClearanceMap(OccupancyGrid.from_occupied(occ, 0.05))
    poses = np.array([[2.55, 2.0, 0.0], [2.5, 2.0, 0.0]])
    assert clear.footprint_distances(robot.footprint_polygon, poses)[0] == pytest.approx(0.15)
    lower = np.array([-0.5, -0.4])
    assert clear.least_footprint_distance(robot.footprint_polygon, poses, lower, reach_m=0.1) == 0.1
    assert clear.least_footprint_distance(robot.footprint_polygon, poses, lower, reach_m=1.0) == pytest.approx(0.15)
    # 0.7 m from the wall with a bound of −0.5: the measure within 0.2 m falls short, the full reach finds 0.7
    assert clear.least_footprint_distance(robot.footprint_polygon, np.array([[2.0, 2.0, 0.0]]), np.array([-0.5]),
                                          reach_m=1.0) == pytest.approx(0.7)


def test_leaving_the_map_is_a_collision():
    grid = OccupancyGrid.from_occupied(np.zeros((40, 40), bool), 0.1)
    fp = CircleFootprint.for_robot(load_robot())
    clear = ClearanceMap(grid)
    assert clear.circle_margins(fp, np.array([[2.0, 2.0, 0.0]]))[0] > 0
    assert clear.circle_margins(fp, np.array([[0.2, 2.0, 0.0]]))[0] < 0
    assert clear.circle_margins(fp, np.array([[-1.0, 2.0, math.pi]]))[0] == -math.inf


def test_footprint_clearance_against_a_wall() -> None:
    ROBOT = _box_robot(0.3, 0.35)
    occ = np.zeros((80, 80), dtype=bool)
    occ[:, 60:] = True  # wall from x = 3.0 m
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    half_l, half_w = ROBOT.footprint_length_m / 2, ROBOT.footprint_width_m / 2
    assert least_footprint_distance(grid, ROBOT, np.array([[2.0, 2.0, 0.0]])) == pytest.approx(1.0 - half_l)
    assert least_footprint_distance(grid, ROBOT, np.array([[2.0, 2.0, math.pi / 2]])) == pytest.approx(1.0 - half_w)
    diag = math.hypot(half_l, half_w)
    yaw = math.atan2(half_w, half_l)  # a corner points straight at the wall
    assert least_footprint_distance(grid, ROBOT, np.array([[2.0, 2.0, -yaw]])) == pytest.approx(1.0 - diag)
    assert least_footprint_distance(grid, ROBOT, np.array([[2.8, 2.0, 0.0]])) == 0.0
    # the map's edge counts as an obstacle (y = 0 is the bottom edge)
    assert least_footprint_distance(grid, ROBOT, np.array([[1.0, 0.5, 0.0]])) == pytest.approx(0.5 - half_w)


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


def test_the_compiled_distance_transform_equals_scipys():
    from scipy.ndimage import distance_transform_edt

    from planner.maps.clearance import edt_cells

    rng = np.random.default_rng(21)
    for shape, share in (((7, 9), 0.1), ((50, 80), 0.02), ((120, 90), 0.3), ((1, 5), 0.0), ((30, 30), 0.0),
                         ((16, 16), 1.0)):
        blocked = rng.random(shape) < share
        ref = distance_transform_edt(~np.pad(blocked, 1, constant_values=True))[1:-1, 1:-1]
        assert np.array_equal(edt_cells(blocked), ref)


@njit(cache=True)
def _hits_every_cell(blocked, ox, oy, res, x, y, yaw, px, py):
    """The plain exact test: every blocked cell of the polygon's bounding box against the even-odd rule and
    every edge (what :func:`footprint_hits` computed before it was reorganised for speed)."""
    c, s = math.cos(yaw), math.sin(yaw)
    wx, wy = x + c * px - s * py, y + s * px + c * py
    n = px.size
    h, w = blocked.shape
    ix0, ix1 = int(math.floor((wx.min() - ox) / res)), int(math.floor((wx.max() - ox) / res))
    iy0, iy1 = int(math.floor((wy.min() - oy) / res)), int(math.floor((wy.max() - oy) / res))
    if ix0 < 0 or iy0 < 0 or ix1 >= w or iy1 >= h:
        return True
    for iy in range(iy0, iy1 + 1):
        by0 = oy + iy * res
        for ix in range(ix0, ix1 + 1):
            if not blocked[iy, ix]:
                continue
            bx0 = ox + ix * res
            if _point_in_polygon(bx0 + 0.5 * res, by0 + 0.5 * res, wx, wy):
                return True
            j = n - 1
            for i in range(n):
                if _segment_meets_box(wx[j], wy[j], wx[i], wy[i], bx0, by0, bx0 + res, by0 + res):
                    return True
                j = i
    return False


@pytest.mark.parametrize("robot", [load_robot("zju-60"), _box_robot(0.6, 0.2, 0.02)], ids=["zju-60", "box"])
def test_compiled_footprint_tests_give_the_plain_tests_answers(robot: RobotProfile) -> None:
    """footprint_hits (row crossings, edges only near their cells) answers as the plain every-cell test, and
    footprint_distance (cells pruned by the polygon's bounding box) returns the unpruned distance, on poses
    where the footprint touches obstacles (the search calls them there), cell corners and edges included."""
    rng = np.random.default_rng(7)
    occ = rng.random((120, 120)) < 0.002  # lone cells (islands a footprint can cover) and a block
    occ[40:60, 50:90] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    clear = ClearanceMap(grid)
    poly = robot.footprint_polygon
    px, py = np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1])
    rng = np.random.default_rng(8)
    poses = np.column_stack([rng.uniform(0.2, 5.8, 6000), rng.uniform(0.2, 5.8, 6000), rng.uniform(-3.2, 3.2, 6000)])
    poses[:500, :2] = np.round(poses[:500, :2] / grid.resolution_m) * grid.resolution_m  # on cell corners
    poses[:500, 2] = rng.choice([0.0, math.pi / 2, math.pi, -math.pi / 2], 500)
    args = (clear.blocked, clear.origin_x, clear.origin_y, clear.resolution_m)
    turn = convex_turn(px, py)
    hits = 0
    for x, y, yaw in poses:
        fast = footprint_hits_compiled(*args, x, y, yaw, px, py)
        assert fast == _hits_every_cell(*args, x, y, yaw, px, py), (x, y, yaw)
        assert footprint_hits_compiled(*args, x, y, yaw, px, py, turn) == fast  # the convexity given, as the search
        hits += fast
    assert 0.1 * len(poses) < hits < 0.9 * len(poses)  # both answers are well represented
    dist = clear.footprint_distances(poly, poses[:1500], reach_m=1.0)
    for pose, d in zip(poses[:1500], dist, strict=True):
        assert d == pytest.approx(footprint_distance(grid, robot, pose[None], reach_m=1.0), abs=1e-9)


def test_least_footprint_distance_is_zero_for_a_footprint_over_an_obstacle() -> None:
    """A blocked cell wholly inside the footprint (no vertex in it, no edge across it): the least distance is 0, also
    when that pose is not the first measured (valid but loose lower bounds: a free pose's first). Only poses whose
    lower bound is above 0 skip the overlap test (the measure from the polygon's outline alone would put that cell
    about 0.25 m away)."""
    robot = _box_robot(0.3, 0.3)
    occ = np.zeros((60, 60), dtype=bool)
    occ[30, 30] = True  # the cell [1.50, 1.55] × [1.50, 1.55]
    clear = ClearanceMap(OccupancyGrid.from_occupied(occ, 0.05))
    poses = np.array([[0.8, 0.8, 0.0], [1.525, 1.525, 0.1]])
    free = clear.footprint_distances(robot.footprint_polygon, poses[:1], reach_m=1.0)[0]
    assert 0.3 < free < 1.0
    assert clear.least_footprint_distance(robot.footprint_polygon, poses, np.array([-0.5, -0.1])) == 0.0


_L_SHAPE = np.array([[0.3, -0.2], [0.3, 0.0], [0.0, 0.0], [0.0, 0.3], [-0.2, 0.3], [-0.2, -0.2]])
_STAR = np.array([[0.3 * math.cos(a), 0.3 * math.sin(a)] for a in np.arange(5) * 4 * math.pi / 5])  # winds twice


def test_convex_turn_tells_convex_polygons_and_their_orientation() -> None:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    with_a_straight_vertex = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    for poly, want in ((square, 1), (square[::-1], -1), (with_a_straight_vertex, 1),
                       (load_robot("zju-60").footprint_polygon, None), (_L_SHAPE, 0), (_L_SHAPE[::-1], 0),
                       (_STAR, 0), (square[:2], 0)):
        got = convex_turn(np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1]))
        assert got == want if want is not None else got in (1, -1), (poly, got)


@pytest.mark.parametrize("poly", [_L_SHAPE, _STAR, _L_SHAPE[::-1]], ids=["L", "star", "L clockwise"])
def test_a_footprint_that_is_not_convex_gets_the_plain_tests_answer(poly: np.ndarray) -> None:
    """The separating-edge test holds for convex polygons only: any other footprint takes the even-odd rule and
    the clipped edges, and answers as the every-cell test (an L's notch over a lone cell is free)."""
    rng = np.random.default_rng(9)
    occ = rng.random((80, 80)) < 0.01
    clear = ClearanceMap(OccupancyGrid.from_occupied(occ, 0.05))
    px, py = np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1])
    args = (clear.blocked, clear.origin_x, clear.origin_y, clear.resolution_m)
    answers = set()
    for x, y, yaw in zip(rng.uniform(0.5, 3.5, 3000), rng.uniform(0.5, 3.5, 3000), rng.uniform(-3.2, 3.2, 3000),
                         strict=True):
        fast = footprint_hits_compiled(*args, x, y, yaw, px, py)
        assert fast == _hits_every_cell(*args, x, y, yaw, px, py), (x, y, yaw)
        answers.add(fast)
    assert answers == {True, False}


@pytest.mark.parametrize("poly", [_box_robot(0.3, 0.2, 0.02).footprint_polygon[::-1], _L_SHAPE, _L_SHAPE[::-1]],
                         ids=["box clockwise", "L", "L clockwise"])
def test_exact_footprint_distance_of_any_winding_agrees_with_brute_force(poly: np.ndarray) -> None:
    """The distance skips the edges a cell corner lies inside of only for a convex polygon, by its winding: a
    clockwise box and an L (which skips none) measure as the brute force does."""
    occ = np.zeros((100, 100), bool)
    occ[40:45, 30:70] = True
    occ[60:90, 62:64] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    clear = ClearanceMap(grid)
    shape = types.SimpleNamespace(footprint_polygon=np.asarray(poly, float))
    rng = np.random.default_rng(11)
    poses = np.column_stack([rng.uniform(0.5, 4.5, 40), rng.uniform(0.5, 4.5, 40), rng.uniform(-3.2, 3.2, 40)])
    fast = clear.footprint_distances(poly, poses, reach_m=1.0)
    assert 0.05 < np.median(fast) < 1.0
    for pose, d in zip(poses, fast, strict=True):
        assert d == pytest.approx(footprint_distance(grid, shape, pose[None], reach_m=1.0), abs=1e-9)


_OFF_CENTRE = np.array([[0.2, -0.15], [0.6, -0.15], [0.6, 0.15], [0.2, 0.15]])  # the pose 0.2 m outside it


@pytest.mark.parametrize("reach", [0.05, 0.1, 0.3, 1.0, 2.0])
@pytest.mark.parametrize("poly", [_OFF_CENTRE, _L_SHAPE, _box_robot(0.3, 0.2, 0.02).footprint_polygon],
                         ids=["off centre", "L", "box"])
def test_exact_footprint_distance_within_any_reach_agrees_with_brute_force(poly: np.ndarray, reach: float) -> None:
    """The distance's pruning (cells beyond the best so far, by the polygon's box and by the pose's distance less the
    polygon's reach) holds for every reach and for a pose outside its own polygon: the brute force's distance, next to
    walls, a thin post and lone cells, far and near."""
    rng = np.random.default_rng(21)
    occ = rng.random((100, 100)) < 0.003
    occ[40:45, 30:70] = True
    occ[60:90, 62:64] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    clear = ClearanceMap(grid)
    shape = types.SimpleNamespace(footprint_polygon=np.asarray(poly, float))
    poses = np.column_stack([rng.uniform(0.3, 4.7, 200), rng.uniform(0.3, 4.7, 200), rng.uniform(-3.2, 3.2, 200)])
    fast = clear.footprint_distances(poly, poses, reach_m=reach)
    assert np.sum((fast > 0.0) & (fast < reach)) >= 3  # (distances measured, not only overlaps and caps)
    for pose, d in zip(poses, fast, strict=True):
        assert d == pytest.approx(footprint_distance(grid, shape, pose[None], reach_m=reach), abs=1e-9)


def _turning_path(x0: float, y0: float, yaw0: float, n: int, step: float, curvature: float) -> np.ndarray:
    """Poses ``step`` apart along an arc (rows x, y, yaw), the last ones turning on the spot."""
    poses = np.empty((n, 3))
    x, y, yaw = x0, y0, yaw0
    for k in range(n):
        poses[k] = x, y, yaw
        if k < n - 20:
            x, y = x + step * math.cos(yaw), y + step * math.sin(yaw)
            yaw += curvature * step
        else:
            yaw += 0.05
    return poses


def test_path_margins_measure_where_they_must_and_bound_the_rest() -> None:
    """The exact check of a path: measured poses hold their footprint margin, the others a lower bound of their
    footprint distance, above 0; a pose that collides is always found; the least distance is the same."""
    robot = _box_robot(0.6, 0.2, 0.02)  # three covering circles: turning moves the outer ones
    fp = CircleFootprint.for_robot(robot)
    assert fp.offsets_x.size > 1
    occ = np.zeros((160, 160), bool)
    occ[70:74, 20:140] = True  # a wall along y = 3.5 m
    clear = ClearanceMap(OccupancyGrid.from_occupied(occ, 0.05))
    poly = robot.footprint_polygon
    for path in (_turning_path(1.0, 1.0, 0.3, 400, 0.0125, 0.4), _turning_path(1.5, 6.0, -0.2, 300, 0.0125, -0.3),
                 _turning_path(2.0, 2.6, 0.0, 300, 0.0125, 0.0)):
        margins, measured = clear.path_margins(fp, poly, path)
        every = clear.footprint_margins(fp, poly, path)
        exact = clear.footprint_distances(poly, path, reach_m=2.0)
        assert np.array_equal(margins[measured], every[measured])
        assert np.all(margins[~measured] > 0.0)
        assert np.all(margins <= exact + 1e-9)  # a lower bound everywhere (turning included)
        assert (margins.min() < 0) == (every.min() < 0)
        assert clear.least_footprint_distance(poly, path, margins, 2.0, fp, measured) == pytest.approx(
            clear.least_footprint_distance(poly, path, every, 2.0), abs=1e-12)
    # heading for the wall: the nearest pose is one only bounded, and the least distance still finds it
    towards = np.column_stack([np.full(81, 2.0), np.linspace(1.5, 2.5, 81), np.full(81, math.pi / 2)])
    margins, measured = clear.path_margins(fp, poly, towards)
    exact = clear.footprint_distances(poly, towards, reach_m=2.0)
    assert not measured[np.argmin(exact)]
    assert clear.least_footprint_distance(poly, towards, margins, 2.0, fp, measured) == pytest.approx(
        exact.min(), abs=1e-12)
    # in the open most poses are bounded, not measured; into the wall the collision is found
    open_path = _turning_path(2.0, 5.5, 0.0, 300, 0.0125, 0.0)
    assert clear.path_margins(fp, poly, open_path)[1].mean() < 0.1
    into = _turning_path(2.0, 2.0, math.pi / 2, 200, 0.0125, 0.0)
    assert clear.footprint_margins(fp, poly, into).min() < 0
    assert clear.path_margins(fp, poly, into)[0].min() < 0


@pytest.mark.parametrize("robot", [load_robot("zju-60"), _box_robot(0.6, 0.2, 0.02)], ids=["zju-60", "box"])
def test_the_least_distance_of_a_path_is_its_nearest_poses_exact_distance(robot: RobotProfile) -> None:
    """A plan's clearance report (path_margins, then least_footprint_distance with the poses only bounded measured in
    order of their margins) is the least exact distance over every pose, to the bit: 60 paths of random turns
    among random blocks, in the open (nearest obstacle up to 2 m away, the plan's reach) and close by."""
    rng = np.random.default_rng(5)
    occ = np.zeros((240, 240), bool)
    for _ in range(8):
        x, y = rng.integers(0, 230, 2)
        occ[y:y + rng.integers(2, 12), x:x + rng.integers(2, 12)] = True
    clear = ClearanceMap(OccupancyGrid.from_occupied(occ, 0.05))
    fp = CircleFootprint.for_robot(robot)
    poly = robot.footprint_polygon
    far = 0
    for _ in range(60):
        path = _turning_path(rng.uniform(2.5, 9.5), rng.uniform(2.5, 9.5), rng.uniform(-3.1, 3.1), 200, 0.0125,
                             rng.uniform(-0.8, 0.8))
        exact = clear.footprint_distances(poly, path, reach_m=2.0)
        margins, measured = clear.path_margins(fp, poly, path)
        assert clear.least_footprint_distance(poly, path, margins, 2.0, fp, measured) == exact.min()
        far += exact.min() > 0.5
    assert 10 <= far <= 50  # both kinds of path are here


@pytest.mark.parametrize("robot", [load_robot("zju-60"), _box_robot(0.6, 0.2, 0.02)], ids=["zju-60", "box"])
def test_circles_proven_clear_within_their_cells_are_clear(robot: RobotProfile) -> None:
    """circles_clear_at proves a pose free from where each circle's centre lies in its cell, where the circle
    margin (the cell's worst point) says "maybe": never a pose whose polygon meets a blocked cell (random cells,
    and walls at any angle), and some of the "maybe" poses along the walls that fit (a tenth here)."""
    from planner.maps.clearance import circle_margin_at, circles_clear_at

    walls = np.zeros((150, 150), bool)
    walls[30:34, 10:140] = True
    walls[60:140, 70:73] = True
    rows, cols = np.mgrid[0:150, 0:150]
    walls |= np.abs((rows - 100) - 0.6 * (cols - 20)) < 1.5  # a slanted wall
    for grid, n, walled in ((_random_world(5), 8000, False), (OccupancyGrid.from_occupied(walls, 0.05), 30000, True)):
        clear = ClearanceMap(grid)
        fp = CircleFootprint.for_robot(robot)
        rng = np.random.default_rng(6)
        size = grid.size_m
        maybe_free = proven = 0
        for x, y, yaw in zip(rng.uniform(0.3, size[0] - 0.3, n), rng.uniform(0.3, size[1] - 0.3, n),
                             rng.uniform(-3.2, 3.2, n), strict=True):
            c, s = math.cos(yaw), math.sin(yaw)
            args = (clear.clearance, clear.origin_x, clear.origin_y, clear.resolution_m, x, y, c, s, fp.offsets_x,
                    fp.offsets_y, fp.radius_m)
            if circle_margin_at(*args) >= 0.0:
                continue
            hit = footprint_hits(grid, robot, x, y, yaw)
            if circles_clear_at(*args):
                assert not hit, (x, y, yaw)
                proven += 1
            maybe_free += not hit
        if walled:
            assert maybe_free > 300 and proven > 0.05 * maybe_free, (maybe_free, proven)
