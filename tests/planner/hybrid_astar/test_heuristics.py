"""The holonomic heuristic never exceeds the true cost."""

import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from planner.hybrid_astar.heuristics import SIXTEEN_CONNECTED_RATIO, HolonomicHeuristic
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot


def test_never_exceeds_euclidean_in_open_space():
    grid = OccupancyGrid.from_occupied(np.zeros((200, 200), bool), 0.05)
    planner = HybridAStar(grid, load_robot(), PlannerOptions(cost_penalty=0.0))
    goal = (5.0, 5.0)
    h = planner.holonomic(goal)
    rng = np.random.default_rng(5)
    for x, y in rng.uniform(1.0, 9.0, (500, 2)):
        assert h(x, y) <= math.hypot(x - goal[0], y - goal[1]) + 1e-9


def _geodesic_around(p, g, obstacle):
    """Shortest path length from p to g around a convex obstacle (polygon points) that blocks the segment:
    the shorter chain between p and g on the convex hull of the obstacle and both points."""
    pts = np.vstack([obstacle, p, g])
    hull = ConvexHull(pts).vertices.tolist()
    ip, ig = hull.index(len(pts) - 2), hull.index(len(pts) - 1)
    ring = pts[hull]
    seg = np.hypot(*np.diff(np.vstack([ring, ring[:1]]), axis=0).T)
    i, j = sorted((ip, ig))
    one_way = seg[i:j].sum()
    return min(one_way, seg.sum() - one_way)


def test_never_exceeds_the_geodesic_around_a_wall():
    """Every valid pose keeps the centre circle (radius r_c, at the robot's centre) off the wall, so a
    path's length is at least the geodesic of a point around the wall inflated by r_c. With no proximity
    cost that is a lower bound of the true cost; the heuristic may not exceed it."""
    occ = np.zeros((240, 240), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[0:160, 115:125] = True                # wall x ∈ [5.75, 6.25], y ∈ [0, 8]
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    planner = HybridAStar(grid, load_robot(), PlannerOptions(cost_penalty=0.0))
    r_c = planner.footprint.radius_m
    assert np.min(np.hypot(planner.footprint.offsets_x, planner.footprint.offsets_y)) == 0.0
    angles = np.linspace(0, 2 * np.pi, 721)
    # polygon inscribed in (wall ⊕ disk r_c): a lower bound of the true inflated obstacle
    corners = [(5.75, 8.0), (6.25, 8.0), (5.75, -1e4), (6.25, -1e4)]  # the wall meets the border: no way below
    inflated = np.vstack([np.column_stack([cx + r_c * np.cos(angles), cy + r_c * np.sin(angles)])
                          for cx, cy in corners])
    goal = (10.0, 2.0)
    h = planner.holonomic(goal)
    rng = np.random.default_rng(9)
    checked = 0
    for x, y in rng.uniform([0.5, 0.5], [5.3, 7.5], (300, 2)):
        if not math.isfinite(h(x, y)):
            continue
        assert h(x, y) <= _geodesic_around((x, y), goal, inflated) + 1e-9
        checked += 1
    assert checked > 100


def test_heuristic_is_not_trivially_small():
    """A heuristic of zero would pass the bounds above: it must also be close to the geodesic."""
    grid = OccupancyGrid.from_occupied(np.zeros((200, 200), bool), 0.05)
    planner = HybridAStar(grid, load_robot(), PlannerOptions(cost_penalty=0.0))
    h = planner.holonomic((5.0, 5.0))
    assert h(9.0, 5.0) >= 0.85 * 4.0


def test_cut_off_wavefront_is_a_lower_bound_of_the_full_one():
    occ = np.zeros((300, 400), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[0:200, 195:205] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    planner = HybridAStar(grid, load_robot())
    goal, start = (3.0, 3.0), (6.0, 4.0)
    origin, cell = (planner.clearance.origin_x, planner.clearance.origin_y), 0.05 * planner.heuristic_factor
    full = HolonomicHeuristic(planner.holonomic_mult, origin, cell, goal).table
    heur = HolonomicHeuristic(planner.holonomic_mult, origin, cell, goal, start)
    cut = heur.table
    finite = np.isfinite(full)
    assert np.all(cut[finite] <= full[finite] + 1e-9)
    assert np.isfinite(cut[finite]).all()
    # exact wherever cost + distance to the start's cell stays below the bound (the A*'s ellipse)
    sx, sy = (math.floor((start[0] - origin[0]) / cell), math.floor((start[1] - origin[1]) / cell))
    iy, ix = np.indices(full.shape)
    raw = (full + 2.0 * math.sqrt(2.0) * cell) * SIXTEEN_CONNECTED_RATIO
    near = finite & (full > 0) & (raw + cell * np.hypot(ix - sx, iy - sy) < heur.bound - cell)
    assert near.sum() > 500
    assert np.allclose(cut[near], full[near])
    assert (cut < full - 1e-6).any()  # the far side really was cut off
    assert heur.expanded < 0.5 * np.isfinite(planner.holonomic_mult).sum()


def test_reeds_shepp_table_never_exceeds_ompl():
    """Each bin of the table holds the minimum of its corner samples: a lookup anywhere inside the bin is
    at most OMPL's Reeds–Shepp distance at that pose (and close to it)."""
    from ompl import base as ob

    from planner.hybrid_astar.heuristics import reeds_shepp_table

    rho, n_yaw, cell = 1.12, 72, 0.1
    table = reeds_shepp_table(rho, n_yaw, cell)
    n = table.shape[2] // 2
    space = ob.ReedsSheppStateSpace(rho)
    state, goal = space.allocState(), space.allocState()
    goal.setX(0.0)
    goal.setY(0.0)
    goal.setYaw(0.0)
    rng = np.random.default_rng(4)
    gaps = []
    for x, y, yaw in zip(rng.uniform(-n * cell, n * cell, 3000), rng.uniform(-n * cell, n * cell, 3000),
                         rng.uniform(-math.pi, math.pi, 3000), strict=True):
        state.setX(x)
        state.setY(y)
        state.setYaw(yaw)
        i, j = math.floor(x / cell + n), math.floor(y / cell + n)
        k = min(math.floor((yaw + math.pi) / (2 * math.pi) * n_yaw), n_yaw - 1)
        gaps.append(space.distance(state, goal) - table[k, j, i])
    assert min(gaps) >= -1e-9
    assert np.mean(gaps) < 0.25


def test_weighted_reeds_shepp_table_never_exceeds_the_cheapest_weighted_word():
    """With the search's reverse and cusp weights each bin holds at most the cheapest word's weighted cost
    (:func:`rs_best`) anywhere inside it, and it is above the plain distance where reversing or a cusp is needed."""
    from planner.hybrid_astar.heuristics import reeds_shepp_table
    from planner.hybrid_astar.reeds_shepp import rs_best

    rho, n_yaw, cell, rp, sc = 1.12, 72, 0.1, 1.2, 1.0
    table = reeds_shepp_table(rho, n_yaw, cell, reverse_penalty=rp, switch_cost_m=sc)
    plain = reeds_shepp_table(rho, n_yaw, cell)
    assert table.shape == plain.shape
    assert np.all(table >= plain - 1e-9)  # every weight is ≥ 1: never below the distance
    n = table.shape[2] // 2
    seg_turn, seg_len = np.zeros(6), np.zeros(6)
    rng = np.random.default_rng(5)
    gaps = []
    for x, y, yaw in zip(rng.uniform(-n * cell, n * cell, 20000), rng.uniform(-n * cell, n * cell, 20000),
                         rng.uniform(-math.pi, math.pi, 20000), strict=True):
        i, j = math.floor(x / cell + n), math.floor(y / cell + n)
        k = min(math.floor((yaw + math.pi) / (2 * math.pi) * n_yaw), n_yaw - 1)
        _, cost = rs_best(x, y, yaw, 0.0, 0.0, 0.0, rho, rp, sc, seg_turn, seg_len)
        gaps.append(cost - table[k, j, i])
    assert min(gaps) >= -1e-9
    assert np.mean(gaps) < 0.35
    # 2 m straight ahead of the goal, same heading: reversing costs 1.2 × 2 m, turning round far more
    i, j, k = round(2.0 / cell + n), n, n_yaw // 2
    assert table[k, j, i] == pytest.approx(rp * 2.0, abs=2.5 * cell)
    assert plain[k, j, i] == pytest.approx(2.0, abs=2.5 * cell)


def test_reeds_shepp_table_is_mirror_symmetric():
    """The build computes half the yaw samples and mirrors the rest ((x, y, yaw) ↔ (x, −y, −yaw)): the mirrored
    half must equal what the words give there."""
    from planner.hybrid_astar.heuristics import _word_costs

    rho, n_yaw = 1.12, 72
    coords = (np.arange(11) - 5) * 0.3
    for k in (5, 20, 33):
        yaw = -math.pi + 2 * math.pi * k / n_yaw
        a, b = np.empty((11, 11)), np.empty((11, 11))
        c, d = np.empty((11, 11)), np.empty((11, 11))
        _word_costs(yaw, coords, rho, 1.2, 1.0, a, b)
        _word_costs(-yaw, coords, rho, 1.2, 1.0, c, d)
        assert np.allclose(a, c[::-1], atol=1e-9) and np.allclose(b, d[::-1], atol=1e-9)


def test_reverse_search_uses_reeds_shepp_and_stays_valid():
    from tests.pathcheck import check_path

    occ = np.zeros((160, 160), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    planner = HybridAStar(grid, load_robot(), PlannerOptions(allow_reverse=True))
    assert planner.rs_table.shape[0] == PlannerOptions().n_yaw_bins
    start, goal = (4.0, 4.0, 0.0), (3.0, 4.0, 0.0)      # one metre straight behind: reversing is best
    result = planner.plan(start, goal)
    assert check_path(grid, planner.robot, result.states, start, goal) == []
    assert (result.states[:, 4] < 0).any()              # it does reverse
    assert result.length_m < 2.0


def test_holonomic_tables_are_cached_per_goal_and_replaced_when_the_start_is_beyond_their_cut_off():
    occ = np.zeros((200, 400), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    planner = HybridAStar(OccupancyGrid.from_occupied(occ, 0.05), load_robot())
    goal = (18.0, 5.0)
    near = planner.holonomic(goal, (15.0, 5.0))
    assert planner.holonomic((18.01, 5.0), (15.5, 4.0)) is near  # same goal cell, start inside the settled part
    assert near.covers((15.5, 4.0)) and not near.covers((1.0, 5.0))  # the far end lies beyond the exact part
    assert near(1.0, 5.0) < 12.0  # only a lower bound there
    far = planner.holonomic(goal, (1.0, 5.0))
    assert far is not near and far.covers((1.0, 5.0))
    assert planner.holonomic(goal, (1.0, 5.0)) is far
    assert far(1.0, 5.0) > near(1.0, 5.0)  # better informed there, and still a lower bound of the true cost
    assert far(1.0, 5.0) <= 17.0


def test_the_weighted_table_is_used_only_when_asked():
    from planner.hybrid_astar.heuristics import reeds_shepp_table

    occ = np.zeros((60, 60), bool)
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    robot = load_robot()
    rho = robot.min_turning_radius_m
    plain = HybridAStar(grid, robot, PlannerOptions(allow_reverse=True))
    weighted = HybridAStar(grid, robot, PlannerOptions(allow_reverse=True, weighted_rs_heuristic=True,
                                                       reverse_penalty=1.5, switch_cost_m=2.0))
    bins = PlannerOptions().n_yaw_bins
    assert plain.rs_table is reeds_shepp_table(rho, bins, 0.1)
    assert weighted.rs_table is reeds_shepp_table(rho, bins, 0.1, reverse_penalty=1.5, switch_cost_m=2.0)
    assert weighted.rs_table.max() > plain.rs_table.max()
