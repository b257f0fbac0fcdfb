"""The holonomic heuristic never exceeds the true cost."""

import math

import numpy as np

from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.search import HybridAStar, PlannerOptions


def _heuristic(planner, goal, opts):
    return planner.holonomic(goal)


def test_never_exceeds_euclidean_in_open_space():
    grid = OccupancyGrid.from_occupied(np.zeros((200, 200), bool), 0.05)
    planner = HybridAStar(grid, load_robot(), PlannerOptions(cost_penalty=0.0))
    goal = (5.0, 5.0)
    h = _heuristic(planner, goal, planner.options)
    rng = np.random.default_rng(5)
    for x, y in rng.uniform(1.0, 9.0, (500, 2)):
        assert h(x, y) <= math.hypot(x - goal[0], y - goal[1]) + 1e-9


def test_never_exceeds_the_planned_cost_with_obstacles():
    occ = np.zeros((240, 240), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[0:160, 115:125] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    opts = PlannerOptions(greed=0.5, smooth=False, time_limit_s=20)
    planner = HybridAStar(grid, load_robot(), opts)
    goal = (10.0, 2.0, 0.0)
    h = _heuristic(planner, goal[:2], opts)
    rng = np.random.default_rng(9)
    checked = 0
    while checked < 4:
        x, y = rng.uniform(1.0, 4.0), rng.uniform(6.0, 10.5)
        if planner.pose_margin((x, y, 0.0)) < 0.1:
            continue
        result = planner.plan((x, y, 0.0), goal)
        assert h(x, y) <= result.length_m + 1e-9
        checked += 1


def test_cut_off_wavefront_is_a_lower_bound_of_the_full_one():
    occ = np.zeros((300, 400), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[0:200, 195:205] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    planner = HybridAStar(grid, load_robot())
    goal, start = (3.0, 3.0), (6.0, 4.0)
    full = planner.holonomic(goal).table
    cut = planner.holonomic(goal, start).table
    finite = np.isfinite(full)
    assert np.all(cut[finite] <= full[finite] + 1e-9)
    assert np.isfinite(cut[finite]).all()
    h_start = planner.holonomic(goal, start)(*start)
    near = full <= 1.5 * h_start
    assert np.allclose(cut[near], full[near])
    assert (cut < full - 1e-6).any()  # the far side really was cut off
