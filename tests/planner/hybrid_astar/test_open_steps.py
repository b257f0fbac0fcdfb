"""Long steps in the open (PlannerOptions.open_step_factor, kernels.search_chunk stage 4): where the node's clearance
leaves room for the longer arc, a child rolls several steps at once. Fewer expansions, the same kind of path,
checked by the independent path check; the motions rebuilt from the nodes hold the right lengths."""

import math

import numpy as np
import pytest

from planner.errors import InvalidInput
from planner.hybrid_astar import kernels
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, _Search
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path

ROBOT = load_robot("zju-60")


def _hall():
    """A 30 m × 12 m hall with a wall across it, open at one end."""
    occupied = np.zeros((240, 600), bool)
    occupied[:, :2] = occupied[:, -2:] = occupied[:2, :] = occupied[-2:, :] = True
    occupied[:170, 290:300] = True
    return OccupancyGrid.from_occupied(occupied, 0.05, name="hall")


@pytest.mark.parametrize("start,goal", [((2.0, 2.0, 0.0), (28.0, 2.0, 0.0)),
                                        ((3.0, 3.0, math.pi / 2), (27.0, 2.5, -math.pi / 2))])
def test_long_steps_in_the_open_take_fewer_expansions_for_a_path_as_long(start, goal):
    grid = _hall()
    short = HybridAStar(grid, ROBOT, PlannerOptions(open_step_factor=1)).plan(start, goal)
    long = HybridAStar(grid, ROBOT, PlannerOptions(open_step_factor=3)).plan(start, goal)
    assert long.expansions < 0.6 * short.expansions
    assert long.length_m < 1.05 * short.length_m
    assert check_path(grid, ROBOT, long.states, start, goal) == []


def test_the_motions_of_long_steps_roll_to_the_nodes_the_search_made():
    grid = _hall()
    planner = HybridAStar(grid, ROBOT, PlannerOptions(open_step_factor=3))
    start, goal = (2.0, 2.0, 0.0), (28.0, 2.0, 0.0)
    run = _Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), planner.options, planner.reverse)
    assert planner._drive(run, start, goal, planner.options, Termination().start()) is None
    k = int(run.counters[kernels.C_RESULT])
    motions = planner._chain(run, k)
    lengths = sorted({round(abs(s) / planner.resolved_step_m) for _, _, s in motions})
    assert 3 in lengths and set(lengths) <= {1, 3}  # long steps in the open, one step elsewhere
    # every node on the chain is where its motions roll to (the rebuilt lengths are the lengths searched)
    chain = []
    while k > 0:
        chain.append(k)
        k = int(run.node_i[k, 0])
    for depth, node in enumerate(reversed(chain), start=1):
        end = planner._knots(start, motions[:depth])[-1]
        assert np.allclose(end[:3], run.node_f[node, :3], atol=1e-9)


@pytest.mark.parametrize("value", [0, 9])
def test_open_step_factor_out_of_range_is_refused_by_name(value):
    with pytest.raises(InvalidInput, match=r"options\.open_step_factor"):
        PlannerOptions.from_dict({"open_step_factor": value})
