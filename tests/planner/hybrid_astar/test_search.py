"""The spherical Hybrid A*: valid paths (checked independently), typed failures with Nav2 codes."""

import math
import threading

import numpy as np
import pytest

from planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidInput,
    NoValidPathFound,
    PlannerCancelled,
    PlannerTimedOut,
    StartOccupied,
    StartOutsideMap,
)
from planner.hybrid_astar.search import CLEARANCE_REACH_M, HybridAStar, PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path, footprint_distance


def two_walls(res=0.05, size=400):
    occ = np.zeros((size, size), bool)
    occ[:5] = occ[-5:] = True
    occ[:, :5] = occ[:, -5:] = True
    occ[0:260, 130:140] = True
    occ[140:400, 260:270] = True
    occ[180:230, 50:100] = True
    return OccupancyGrid.from_occupied(occ, res, name="two-walls")


@pytest.fixture(scope="module")
def planner():
    return HybridAStar(two_walls(), load_robot())


@pytest.mark.parametrize(
    ("start", "goal"),
    [((2, 2, 0), (18, 18, math.pi / 2)), ((3, 17, -math.pi / 2), (17, 3, 0.0)), ((2, 2, 0), (4, 2.2, 0.0)),
     ((2, 2, 0), (2.5, 4, math.pi))],
)
def test_paths_are_valid(planner, start, goal):
    result = planner.plan(start, goal)
    assert result.status == "exact" and result.error_code == 0
    assert check_path(planner.grid, planner.robot, result.states, start, goal) == []
    # the reported clearance is the footprint polygon's true distance to the obstacles (the planner samples
    # the path 4× finer than the returned states, so it may find a pose a little closer)
    true = min(footprint_distance(planner.grid, planner.robot, result.states, reach_m=2.5), CLEARANCE_REACH_M)
    assert true - 0.02 <= result.min_clearance_m <= true + 1e-9
    assert result.length_m >= math.hypot(goal[0] - start[0], goal[1] - start[1]) - 0.2


def test_smoothing_shortens_and_keeps_validity(planner):
    start, goal = (2, 2, 0), (18, 18, math.pi / 2)
    rough = HybridAStar(planner.grid, planner.robot, PlannerOptions(smooth=False)).plan(start, goal)
    smooth = planner.plan(start, goal)
    assert smooth.length_m < rough.length_m
    assert check_path(planner.grid, planner.robot, rough.states, start, goal) == []


def test_reverse_option_and_calibrated_robot():
    grid = two_walls()
    for robot, opts in ((load_robot("daedalus"), PlannerOptions()), (load_robot(), PlannerOptions(allow_reverse=True))):
        start, goal = (2, 2, 0), (3, 6, math.pi)
        result = HybridAStar(grid, robot, opts).plan(start, goal)
        assert check_path(grid, robot, result.states, start, goal) == []


def test_expansions_per_metre_in_the_result(planner):
    """Issue 21 item 3: extra["expansions_per_m"] is the expansions over the returned path's length."""
    result = planner.plan((2, 2, 0), (18, 18, math.pi / 2))
    xy = result.states[:, :2]
    polyline = float(np.hypot(*np.diff(xy, axis=0).T).sum())  # the states' chords: within a percent of the arcs
    assert result.expansions > 0
    assert result.extra["expansions_per_m"] == pytest.approx(result.expansions / polyline, rel=0.01)
    here = planner.plan((2, 2, 0), (2, 2, 0))  # already there: no length, no ratio (and no NaN in the JSON)
    assert here.length_m == 0.0 and here.extra["expansions_per_m"] is None


def test_search_loop_time_in_the_result(planner):
    """extra["search_loop_time_s"]: the part of the planning time in the compiled loop (every search of the plan)."""
    result = planner.plan((2, 2, 0), (18, 18, math.pi / 2))
    assert 0.0 < result.extra["search_loop_time_s"] < result.planning_time_s
    here = planner.plan((2, 2, 0), (2, 2, 0))  # a new plan starts from zero
    assert here.extra["search_loop_time_s"] < result.extra["search_loop_time_s"]


def test_same_input_same_path(planner):
    a = planner.plan((2, 2, 0), (18, 18, 1.0))
    b = planner.plan((2, 2, 0), (18, 18, 1.0))
    assert np.array_equal(a.states, b.states)


def test_endpoint_errors_carry_nav2_codes(planner):
    with pytest.raises(StartOutsideMap) as e:
        planner.plan((-1, 2, 0), (5, 5, 0))
    assert e.value.code == 203
    with pytest.raises(GoalOutsideMap) as e2:
        planner.plan((2, 2, 0), (25, 5, 0))
    assert e2.value.code == 204
    with pytest.raises(StartOccupied) as e3:
        planner.plan((6.75, 5, 0), (2, 2, 0))
    assert e3.value.code == 205
    with pytest.raises(GoalOccupied) as e4:
        planner.plan((2, 2, 0), (0.4, 5, 0))
    assert e4.value.code == 206 and "goal" in str(e4.value)
    with pytest.raises(InvalidInput, match="start"):
        planner.plan((float("nan"), 2, 0), (5, 5, 0))


def test_unreachable_goal_is_no_path_quickly():
    occ = np.zeros((200, 200), bool)
    occ[:3] = occ[-3:] = True
    occ[:, :3] = occ[:, -3:] = True
    occ[100:103, 100:200] = True          # a closed room in the upper right
    occ[100:200, 100:103] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    with pytest.raises(NoValidPathFound) as e:
        HybridAStar(grid, load_robot()).plan((2, 2, 0), (7.5, 7.5, 0), Termination(2.0))
    assert e.value.code == 208


def test_narrow_gap_blocks_but_heuristic_lets_search_exhaust():
    """A gap narrower than the footprint: the holonomic grid may pass, the search must say no path."""
    occ = np.zeros((120, 200), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[:, 100:104] = True
    occ[55:67, 100:104] = False           # 0.6 m gap: too narrow for the 0.7 m wide footprint
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    planner = HybridAStar(grid, load_robot())
    with pytest.raises(NoValidPathFound):
        planner.plan((2, 3, 0), (8, 3, 0), Termination(20))


def test_timeout_and_cancel(planner):
    with pytest.raises(PlannerTimedOut) as e:
        HybridAStar(planner.grid, planner.robot, PlannerOptions(greed=0.0, chunk_expansions=50)).plan(
            (2, 2, 0), (18, 18, math.pi / 2), Termination(0.05))
    assert e.value.code == 207
    flag = threading.Event()
    flag.set()
    with pytest.raises(PlannerCancelled):
        HybridAStar(planner.grid, planner.robot, PlannerOptions(greed=0.0, chunk_expansions=50)).plan(
            (2, 2, 0), (18, 18, math.pi / 2), Termination(cancel=flag.is_set))


def test_iteration_cap_comes_from_the_termination(planner):
    with pytest.raises(NoValidPathFound, match="iteration cap of 40 expansions") as e:
        HybridAStar(planner.grid, planner.robot, PlannerOptions(greed=0.0, chunk_expansions=10)).plan(
            (2, 2, 0), (18, 18, math.pi / 2), Termination(max_iterations=40))
    assert e.value.expansions == 40


@pytest.mark.parametrize("key", ["time_limit_s", "max_iterations"])
def test_when_to_stop_is_not_a_planner_option(key):
    with pytest.raises(InvalidInput, match=rf"options\.{key}.*request's own"):
        PlannerOptions.from_dict({key: 1})


def test_options_validation():
    with pytest.raises(InvalidInput, match=r"options\.n_rolls"):
        PlannerOptions.from_dict({"n_rolls": 4})
    with pytest.raises(InvalidInput, match=r"options\.bogus"):
        PlannerOptions.from_dict({"bogus": 1})
    with pytest.raises(InvalidInput, match=r"options\.greed"):
        PlannerOptions.from_dict({"greed": "fast"})
    with pytest.raises(InvalidInput, match=r"options\.time_limit_s"):
        PlannerOptions.from_dict({"time_limit_s": -1.0})
    assert PlannerOptions.from_dict({"greed": 1}).greed == 1.0


def test_more_smoothing_passes_never_lengthen(planner):
    start, goal = (2, 2, 0), (18, 18, math.pi / 2)
    one = planner.plan(start, goal)
    three = HybridAStar(planner.grid, planner.robot, PlannerOptions(smooth_passes=3)).plan(start, goal)
    assert three.length_m <= one.length_m + 1e-9
    assert check_path(planner.grid, planner.robot, three.states, start, goal) == []


def test_roll_bins_in_closed_set():
    opts = PlannerOptions(n_rolls=7, n_roll_bins=3)
    planner = HybridAStar(two_walls(), load_robot(), opts)
    assert planner.roll_bins.tolist() == [0, 0, 1, 1, 1, 2, 2]
    assert planner.roll_bins[3] == 1  # upright in the middle bin
    with pytest.raises(InvalidInput, match=r"options\.n_roll_bins"):
        PlannerOptions.from_dict({"n_roll_bins": 4})


def test_options_that_would_exhaust_memory_or_spin_are_rejected():
    with pytest.raises(InvalidInput, match=r"options\.n_rolls"):
        PlannerOptions.from_dict({"n_rolls": 2000001})
    with pytest.raises(InvalidInput, match=r"options\.chunk_expansions"):
        PlannerOptions.from_dict({"chunk_expansions": 0})
