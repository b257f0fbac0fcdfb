"""Children are checked at their end pose when pushed and their motion is swept when popped (kernels.search_chunk,
1b): a motion that jumps a wall is never expanded, however free both its ends are."""

import dataclasses
import math

import numpy as np
import pytest

from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.pathcheck import check_path
from tests.scenarios import SCENARIO_BINS

# a small footprint (12 cm square) and 0.5 m steps: a child's two ends can lie on either side of a one-cell wall
SMALL = dataclasses.replace(load_robot("zju-60"), footprint=((0.06, 0.06), (-0.06, 0.06), (-0.06, -0.06),
                                                             (0.06, -0.06)), footprint_padding_m=0.0)


@pytest.fixture(scope="module")
def thin_wall() -> OccupancyGrid:
    occ = np.zeros((100, 200), bool)  # 10 m × 5 m at 5 cm
    occ[:80, 100] = True  # a wall one cell thick at x = 5 m, open above y = 4 m
    return OccupancyGrid.from_occupied(occ, 0.05, name="thin-wall")


@pytest.mark.parametrize("reverse", [False, True])
def test_a_long_step_does_not_jump_a_thin_wall(thin_wall, reverse) -> None:
    start, goal = (2.0, 1.0, 0.0), (8.0, 1.0, 0.0)
    options = PlannerOptions(step_m=0.5, allow_reverse=reverse, open_step_factor=1)
    result = HybridAStar(thin_wall, SMALL, options).plan(start, goal)
    assert check_path(thin_wall, SMALL, result.states, start, goal) == []
    # round the wall's end at (5, 4): at least the two straight lines through it
    assert result.length_m > 2 * math.hypot(3.0, 3.0)
    assert float(result.states[:, 1].max()) > 4.0
    assert math.isfinite(result.min_clearance_m)


def test_the_node_storage_does_not_grow_past_the_deadline(monkeypatch) -> None:
    """Growing the search's storage copies every array and cannot be cut short (0.1–0.2 s at a million nodes): it
    grows only when its last growth's time × GROWTH_MARGIN still fits before the plan's deadline, else the plan is
    out of time at once. The admissible search (greed 0) of the two-walls problem pushes nodes by the hundred
    thousand: with the margin made huge it stops at its second growth, long before its limit; with the default it
    grows on and runs into the limit itself."""
    from planner.errors import PlannerTimedOut
    from planner.hybrid_astar import search
    from planner.termination import Termination
    from tests.planner.hybrid_astar.test_search import two_walls

    # (72 heading bins, 11 held rolls, a closed-set bin each: with the defaults the admissible search ended within the
    # 1.5 s below on the machine of issue 21's eighteenth round, once the closed set's cells followed the step)
    planner = HybridAStar(two_walls(), load_robot("zju-60"),
                          PlannerOptions(greed=0.0, n_yaw_bins=SCENARIO_BINS, n_rolls=11, n_roll_bins=0))
    start, goal = (2.0, 2.0, 0.0), (18.0, 18.0, math.pi / 2)
    monkeypatch.setattr(search, "GROWTH_MARGIN", 1e12)
    with pytest.raises(PlannerTimedOut, match="storage of 131072 nodes was full") as err:
        planner.plan(start, goal, Termination(60.0))
    assert err.value.planning_time_s < 30.0
    stopped_at = err.value.expansions
    monkeypatch.setattr(search, "GROWTH_MARGIN", 2.5)
    with pytest.raises(PlannerTimedOut) as err:
        planner.plan(start, goal, Termination(1.5))
    assert err.value.expansions > 2 * stopped_at  # it grew on (where it stops depends on the machine)
