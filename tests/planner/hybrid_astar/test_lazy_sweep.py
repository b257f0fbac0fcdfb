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
