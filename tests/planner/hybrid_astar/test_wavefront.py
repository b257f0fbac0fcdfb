"""The holonomic wavefront (heuristics._wavefront16) against an exact Dijkstra (scipy's), and its work."""

import math

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from planner.hybrid_astar.heuristics import _MOVES, SIXTEEN_CONNECTED_RATIO, HolonomicHeuristic
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot


def _passes(mx: int, my: int) -> list[tuple[int, int]]:
    """The cells a move needs passable besides its target: both cells beside a diagonal, the two a knight
    move crosses."""
    if abs(mx) + abs(my) == 2:
        return [(mx, 0), (0, my)]
    if abs(mx) + abs(my) == 3:
        return [(mx // 2, 0), (mx // 2, my)] if abs(mx) == 2 else [(0, my // 2), (mx, my // 2)]
    return []


def exact_costs(mult: np.ndarray, goal: tuple[int, int], cell_m: float) -> np.ndarray:
    """Cost from the goal cell to every cell over the 16-connected grid, step cost length × cell × the mean of
    the two cells' multipliers, by scipy's Dijkstra (inf where unreachable)."""
    h, w = mult.shape
    ok = np.isfinite(mult)
    rows, cols, costs = [], [], []
    iy, ix = np.nonzero(ok)
    for mx, my in _MOVES:
        nx, ny = ix + mx, iy + my
        inside = (nx >= 0) & (ny >= 0) & (nx < w) & (ny < h)
        keep = inside.copy()
        keep[inside] &= ok[ny[inside], nx[inside]]
        for px, py in _passes(int(mx), int(my)):
            qx, qy = ix + px, iy + py
            keep[keep] &= ok[qy[keep], qx[keep]]
        a = iy[keep] * w + ix[keep]
        b = ny[keep] * w + nx[keep]
        rows.append(a)
        cols.append(b)
        costs.append(math.hypot(mx, my) * cell_m * 0.5 * (mult.ravel()[a] + mult.ravel()[b]))
    graph = csr_matrix((np.concatenate(costs), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w, h * w))
    return dijkstra(graph, directed=True, indices=goal[1] * w + goal[0]).reshape(h, w)


def as_table(raw: np.ndarray, cell_m: float) -> np.ndarray:
    return np.maximum(raw / SIXTEEN_CONNECTED_RATIO - 2.0 * math.sqrt(2.0) * cell_m, 0.0)


def _obstacle_mult() -> tuple[np.ndarray, float]:
    """A planner's coarse multipliers (proximity-weighted, inf in walls) on a map with walls and a box."""
    occ = np.zeros((240, 600), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[0:170, 100:108] = True                # walls at x ≈ 5 m (from below) and 10 m (from above)
    occ[70:240, 200:208] = True
    occ[100:140, 40:70] = True                # a box
    occ[60:180, 400:440] = True
    planner = HybridAStar(OccupancyGrid.from_occupied(occ, 0.05), load_robot(), PlannerOptions(cost_penalty=2.0))
    return planner.holonomic_mult, 0.05 * planner.heuristic_factor


def _cell(xy: tuple[float, float], cell_m: float) -> tuple[int, int]:
    return math.floor(xy[0] / cell_m), math.floor(xy[1] / cell_m)


def test_the_full_table_is_the_exact_cost():
    mult, cell = _obstacle_mult()
    goal = (1.0, 1.0)
    exact = as_table(exact_costs(mult, _cell(goal, cell), cell), cell)
    heur = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal)
    assert np.array_equal(np.isfinite(heur.table), np.isfinite(exact))
    finite = np.isfinite(exact)
    assert np.allclose(heur.table[finite], exact[finite], rtol=0, atol=1e-9)
    assert heur.bound == math.inf and heur.expanded >= finite.sum()


@pytest.mark.parametrize("goal, start, part", [((1.0, 1.0), (7.0, 1.0), 0.5), ((14.0, 10.0), (1.0, 1.0), 1.1),
                                               ((8.0, 4.0), (9.0, 5.0), 0.05), ((25.0, 6.0), (18.0, 6.0), 0.6)])
def test_the_cut_off_table_never_exceeds_the_exact_cost_and_is_exact_around_the_way(goal, start, part):
    """``part``: the most of the passable cells the wavefront may expand (a cell reached more cheaply after it
    was expanded is expanded again, so a table exact nearly everywhere can take a few more than all)."""
    mult, cell = _obstacle_mult()
    raw = exact_costs(mult, _cell(goal, cell), cell)
    exact = as_table(raw, cell)
    heur = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal, start)
    finite = np.isfinite(exact)
    assert np.isfinite(heur.table[finite]).all()
    assert np.all(heur.table[finite] <= exact[finite] + 1e-9)
    # exact where cost + distance to the start's cell is below the bound
    sx, sy = _cell(start, cell)
    iy, ix = np.indices(mult.shape)
    inside = finite & (raw + cell * np.hypot(ix - sx, iy - sy) < heur.bound)
    assert inside[sy, sx]
    assert np.allclose(heur.table[inside], exact[inside], rtol=0, atol=1e-9)
    assert heur.covers(start)
    assert (heur.table[finite] < exact[finite] - 1e-6).any()  # and the rest really was cut off
    assert heur.expanded < part * finite.sum()


def test_steps_longer_than_the_queue_ring_are_still_exact():
    """The only way through a wall is a cell of multiplier 300: a step into it costs ~150 cells, beyond the
    ring's 64 cells of buckets, so it is filed in the ring's last bucket and filed again when popped early.
    Elsewhere multipliers up to 80 in random cells."""
    rng = np.random.default_rng(3)
    mult = 1.0 + 79.0 * (rng.random((60, 70)) < 0.3) * rng.random((60, 70))
    mult[:, 35] = np.inf
    mult[30, 35] = 300.0
    cell = 0.25
    goal = (5 * cell + 0.1, 5 * cell + 0.1)
    exact = as_table(exact_costs(mult, (5, 5), cell), cell)
    finite = np.isfinite(exact)
    assert finite[:, 36:].any()
    for start in (None, (60 * cell, 30 * cell)):
        heur = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal, start)
        assert np.array_equal(np.isfinite(heur.table), finite)
        assert np.all(heur.table[finite] <= exact[finite] + 1e-9)
        assert np.allclose(heur.table[:, :35][finite[:, :35]], exact[:, :35][finite[:, :35]], rtol=0, atol=1e-9)
        if start is None:
            assert np.allclose(heur.table[finite], exact[finite], rtol=0, atol=1e-9)


def test_the_work_is_in_proportion_to_the_part_computed():
    """On a large open grid, a start 5 m from the goal expands the cells of the ellipse around them (about
    π·a·b with a = B/2, b = √(B² − d²)/2, B = STOP_FACTOR·d + STOP_MARGIN_M), a small part of the map, and each
    expanded cell queues about one to two entries; with no start every cell is expanded."""
    from planner.hybrid_astar.heuristics import STOP_FACTOR, STOP_MARGIN_M

    n, cell = 400, 0.1
    mult = np.ones((n, n))
    goal, start = (20.0, 20.0), (25.0, 20.0)
    near = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal, start)
    d = 5.0
    bound = STOP_FACTOR * d + STOP_MARGIN_M
    ellipse = math.pi * (bound / 2) * (math.sqrt(bound ** 2 - d ** 2) / 2) / cell ** 2
    assert 0.8 * ellipse < near.expanded < 1.3 * ellipse
    assert near.expanded < 0.05 * n * n
    assert near.pushes < 3 * near.expanded
    farther = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal, (30.0, 20.0))
    assert 2.5 * near.expanded < farther.expanded < 6 * near.expanded  # the ellipse's area goes as d²
    everywhere = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal)
    assert n * n <= everywhere.expanded < 1.1 * n * n


def test_the_goal_sides_table_is_guided_by_the_forward_one():
    """The table towards the start (the goal side's) takes the forward table, a lower bound of the cost to the
    start's cell, as its A*'s estimate: still never above the exact cost, exact where cost from the start +
    that estimate is below the bound, and fewer cells expanded than with the straight distance alone when the
    forward table is exact well around the way (here 1.3 × + 2 m: with the planner's 1.1 × + 1 m this map's guided
    table expands 3 % more cells than the plain one; on the real maps 20 % fewer, docs/planning.md)."""
    mult, cell = _obstacle_mult()
    goal, start = (25.0, 6.0), (15.0, 3.0)
    forward = HolonomicHeuristic(mult, (0.0, 0.0), cell, goal, start, stop_factor=1.3, stop_margin_m=2.0)
    raw = exact_costs(mult, _cell(start, cell), cell)
    exact = as_table(raw, cell)
    plain = HolonomicHeuristic(mult, (0.0, 0.0), cell, start, goal, stop_factor=1.2)
    guided = HolonomicHeuristic(mult, (0.0, 0.0), cell, start, goal, stop_factor=1.2, guide=forward.table)
    finite = np.isfinite(exact)
    assert np.all(guided.table[finite] <= exact[finite] + 1e-9)
    gx, gy = _cell(goal, cell)
    iy, ix = np.indices(mult.shape)
    lower = np.maximum(cell * np.hypot(ix - gx, iy - gy), forward.table)
    inside = finite & (raw + lower < guided.bound)
    assert inside[gy, gx] and inside.sum() > 1000
    assert np.allclose(guided.table[inside], exact[inside], rtol=0, atol=1e-9)
    assert guided.covers(goal)
    assert guided.expanded < plain.expanded


def test_the_planner_guides_the_goal_sides_table_by_the_cached_forward_one():
    occ = np.zeros((240, 600), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[3:200, 200:220] = True                # a wall from below at x ≈ 10 m: the way goes round its top
    planner = HybridAStar(OccupancyGrid.from_occupied(occ, 0.05), load_robot())
    goal, start = (14.0, 2.0), (6.0, 2.0)
    forward = planner.holonomic(goal, start, 1.5)  # exact well around the way (see the test above)
    back = planner.holonomic(start, goal, 1.2)
    assert back._guide is not None and back._guide() is forward.table
    alone = HolonomicHeuristic(planner.holonomic_mult, (planner.clearance.origin_x, planner.clearance.origin_y),
                               back.cell_m, start, goal, 1.2)
    assert back.expanded < alone.expanded
    full = HolonomicHeuristic(planner.holonomic_mult, (planner.clearance.origin_x, planner.clearance.origin_y),
                              back.cell_m, start).table
    finite = np.isfinite(full)
    assert np.all(back.table[finite] <= full[finite] + 1e-9)
    assert planner.holonomic(start, goal, 1.2) is back  # cached
    planner._heuristics.pop(next(iter(planner._heuristics)))  # the forward table leaves the cache
    del forward
    assert not back.covers(goal)  # its guide is gone with it: the table is not reused
