"""The search's closed set (planner.hybrid_astar.closed_set): a hash set whose size follows the search, not the map."""

from __future__ import annotations

import numpy as np

from planner.hybrid_astar import closed_set
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, _Search
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot


def test_matches_a_python_set_through_growth() -> None:
    rng = np.random.default_rng(3)
    # keys as _closed_key makes them on a 100-million-cell map at 720 yaw bins × 31 roll bins, clustered like a
    # search's (many in a few cells), and a few negative ones (a child off the grid's low edge)
    keys = np.concatenate([rng.integers(0, 100_000_000 * 720 * 31, 3000), rng.integers(5000, 5400, 3000),
                           rng.integers(-300, 0, 200)])
    table = closed_set.new_table(64)
    model: set[int] = set()
    for key in keys.tolist():
        assert closed_set.contains(table, key) == (key in model)
        closed_set.add(table, key)
        model.add(key)
        if 2 * len(model) >= table.size:  # the search keeps the load at most one half
            bigger = closed_set.new_table(table.size)
            closed_set.rehash(table, bigger)
            table = bigger
    assert int((table != closed_set.EMPTY).sum()) == len(model)
    assert all(closed_set.contains(table, k) for k in model)
    others = rng.integers(0, 100_000_000 * 720 * 31, 2000).tolist()
    assert [closed_set.contains(table, k) for k in others] == [k in model for k in others]


def test_new_table_is_a_power_of_two_at_half_load() -> None:
    for capacity in (1, 5, 64, 65, 1000):
        table = closed_set.new_table(capacity)
        assert table.size >= 2 * capacity and table.size & (table.size - 1) == 0 and table.size < 4 * capacity + 2
        assert (table == closed_set.EMPTY).all()


def test_a_search_costs_the_same_memory_on_any_map() -> None:
    """The closed set of a 9-million-cell map at 720 yaw bins × 31 roll bins took a 2.5 GB bitset and was refused;
    now its search holds what a small map's does and plans."""
    robot = load_robot()
    options = PlannerOptions(n_yaw_bins=720, n_rolls=31, n_roll_bins=0)
    sizes = []
    for cells in (200, 3000):
        grid = OccupancyGrid.from_occupied(np.zeros((cells, cells), bool), 0.05)
        planner = HybridAStar(grid, robot, options)
        start, goal = (3.0, 3.0, 0.0), (7.0, 4.0, 0.5)
        sizes.append(_Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), options, True).closed.nbytes)
        result = planner.plan(start, goal)
        assert result.length_m > 4.0
    assert sizes[0] == sizes[1] <= 2**21


def test_the_bitset_and_the_hash_set_make_the_same_search(monkeypatch) -> None:
    """A map under DENSE_MAX_MB gets the bitset; forcing the hash set on it must change no decision."""
    occ = np.zeros((160, 200), bool)
    occ[40:120, 90:96] = True  # a wall to go round
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    robot = load_robot()
    # parked against the wall's face: 2 k expansions from the start alone (the goal side, which joins after 500 and
    # finds the path in under 700, is left out so that the start side's closed set does the work)
    start, goal = (1.5, 4.0, 0.0), (4.0, 4.0, 1.57)
    results = []
    for dense_mb in (closed_set.DENSE_MAX_MB, 0.0):
        monkeypatch.setattr(closed_set, "DENSE_MAX_MB", dense_mb)
        planner = HybridAStar(grid, robot, PlannerOptions(dead_end_check=False))
        run = _Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), planner.options, True)
        assert (run.closed.size > 0) == (dense_mb > 0)
        results.append(planner.plan(start, goal))
    assert results[0].expansions == results[1].expansions > 1000
    np.testing.assert_array_equal(results[0].states, results[1].states)


def test_the_closed_cells_are_half_a_step_in_whole_map_cells() -> None:
    """Issue 21's eighteenth round: the closed set's cell is the map cell × the whole number nearest half the step
    (at least one), so two nodes a step apart never share a cell while states a few centimetres apart do; at 72
    heading bins, or with a step set by option, it is the map cell."""
    import math

    from planner.hybrid_astar import kernels

    robot = load_robot("zju-60")
    grid = OccupancyGrid.from_occupied(np.zeros((100, 100), dtype=bool), 0.05, name="open")
    fine = OccupancyGrid.from_occupied(np.zeros((100, 100), dtype=bool), 0.03, name="fine")
    default = HybridAStar(grid, robot)
    assert default.resolved_step_m == robot.min_turning_radius_m * 2 * math.pi / 36  # 0.195 m
    assert default.closed_cell_m == 2 * 0.05
    assert HybridAStar(fine, robot).closed_cell_m == 3 * 0.03  # 0.195 / 0.06 = 3.3
    assert HybridAStar(grid, robot, PlannerOptions(n_yaw_bins=72)).closed_cell_m == 0.05  # 0.098 / 0.1 = 0.98
    assert HybridAStar(grid, robot, PlannerOptions(step_m=2.0)).closed_cell_m == 0.05
    p = default._params((4.0, 4.0, 0.0), True)
    assert p[kernels.P_CLOSED_CELL] == default.closed_cell_m
    w, step = grid.width, default.resolved_step_m
    key = lambda x, y: kernels._closed_key(p, w, x, y, 0.3, 1, 3)  # noqa: E731
    assert key(2.01, 2.01) == key(2.09, 2.09)  # two map cells apart each way: one closed cell
    for dx, dy in ((step, 0.0), (0.0, step), (step * math.cos(0.8), step * math.sin(0.8))):
        assert key(2.01, 2.01) != key(2.01 + dx, 2.01 + dy)  # a step apart: never the same
