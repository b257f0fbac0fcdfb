"""A search that runs out of states at the default 36 heading bins is run again at 72 before the plan says there is
no path (HybridAStar.plan, SearchRanOut): a start a few centimetres from a wall may have no 0.2 m step that stays
free where a 0.1 m step escapes. Found by the real-map bench's room-matched run (depot#1 of seed 0 at three problems
a map), where BIT* on Reeds–Shepp solves it."""

from __future__ import annotations

import pytest

from lab.planning.real.problems import resolve_map
from planner.errors import NoValidPathFound
from planner.hybrid_astar.search import FINER_BINS, HybridAStar, PlannerOptions, SearchRanOut
from planner.maps.nav2 import load_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path, footprint_distance

ROBOT = load_robot("zju-60")
DEPOT = load_map(resolve_map("depot"))
# 6 cm from a shelf (exact polygon clearance 0.062 m; the covering circles touch it)
TIGHT_START = (18.425, 4.325, -0.7308754819569288)
GOAL = (29.375, 7.125, 3.0211775357715274)


def test_a_start_the_36_bin_search_cannot_leave_is_planned_at_72_bins() -> None:
    planner = HybridAStar(DEPOT, ROBOT)
    with pytest.raises(SearchRanOut) as coarse:  # the search at 36 bins alone
        planner._plan(TIGHT_START, GOAL, Termination(30.0).start())
    assert coarse.value.expansions < 50
    result = planner.plan(TIGHT_START, GOAL, Termination(30.0))
    assert check_path(DEPOT, ROBOT, result.states, TIGHT_START, GOAL) == []
    assert footprint_distance(DEPOT, ROBOT, result.states) > 0.0
    finer = result.extra["finer_search"]
    assert finer["n_yaw_bins"] == FINER_BINS and finer["coarse_expansions"] == coarse.value.expansions
    assert "exhausted" in finer["coarse_reason"] and result.expansions > finer["coarse_expansions"]
    # the finer planner shares the map's preprocessing, and one at 72 bins has no finer one
    assert planner.finer() is planner.finer() and planner.finer().clearance is planner.clearance
    assert planner.finer().holonomic_mult is planner.holonomic_mult
    assert HybridAStar(DEPOT, ROBOT, PlannerOptions(n_yaw_bins=FINER_BINS)).finer() is None


def test_a_goal_no_search_reaches_says_so_with_both_searches_counted() -> None:
    """A forward-only sphere facing out of a dead-end slot it would have to turn inside: both searches prove the
    dead end (the goal side runs dry), and the error counts the expansions of both."""
    import numpy as np

    occ = np.zeros((200, 360), dtype=bool)  # 18 m × 10 m at 5 cm
    occ[150:, 150:154] = True  # a 1.3 m wide slot at the top, x 7.7–9.3 m, its walls from y 7.5 m up
    occ[150:, 186:190] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    start, goal = (15.0, 3.0, 0.0), (8.5, 9.3, 0.0)  # facing a wall, too close to turn without reversing
    planner = HybridAStar(grid, ROBOT, PlannerOptions(allow_reverse=False))
    assert planner.footprint_margin(goal) >= 0
    with pytest.raises(SearchRanOut) as coarse:
        planner._plan(start, goal, Termination(60.0).start())
    with pytest.raises(NoValidPathFound) as both:
        planner.plan(start, goal, Termination(60.0))
    assert not isinstance(both.value, SearchRanOut)  # the caller sees the public error
    assert "at 72 heading bins, as at 36" in str(both.value) and "dead end" in str(both.value)
    assert both.value.expansions > coarse.value.expansions
