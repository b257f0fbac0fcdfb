"""The executed (simulated, closed-loop) trajectory of every shipped solvable problem stays collision-free."""

from functools import cache

import pytest

from planner.closed_loop.simulate import simulate_plan
from planner.hybrid_astar.plan import plan_path
from planner.maps.nav2 import load_map
from planner.maps.problems import list_problems
from planner.robot import load_robot
from planner.termination import Termination

SOLVABLE = [p for p in list_problems() if p.solvable]


@cache
def _grid(path):
    return load_map(path)


@pytest.mark.parametrize("problem", SOLVABLE, ids=[f"{p.map}:{p.name}" for p in SOLVABLE])
def test_executed_trajectory_is_collision_free(problem):
    grid = _grid(problem.map_path)
    robot = load_robot()
    plan = plan_path(grid, robot, problem.start, problem.goal, termination=Termination(problem.time_limit_s)).to_json()
    metrics = simulate_plan(grid, plan, robot, seed=0, noise="none")["metrics"]
    assert not metrics["collided"], metrics
    assert metrics["min_clearance_m"] > 0
    assert metrics["final_position_error_m"] < 0.15
