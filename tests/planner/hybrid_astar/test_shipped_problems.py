"""Every shipped problem: solvable ones give a path the independent checker accepts; unsolvable ones
report "no path" within their time limit."""

import time
from functools import cache

import pytest

from planner.errors import NoValidPathFound
from planner.hybrid_astar.plan import plan_path
from planner.maps.nav2 import load_map
from planner.maps.problems import list_problems
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path

PROBLEMS = list_problems()


@cache
def _grid(path):
    return load_map(path)


def test_problem_sets_have_both_kinds():
    assert sum(p.solvable for p in PROBLEMS) >= 15
    assert sum(not p.solvable for p in PROBLEMS) >= 5


@pytest.mark.parametrize("problem", PROBLEMS, ids=[f"{p.map}:{p.name}" for p in PROBLEMS])
def test_shipped_problem(problem):
    grid = _grid(problem.map_path)
    robot = load_robot()
    if problem.solvable:
        result = plan_path(grid, robot, problem.start, problem.goal, termination=Termination(problem.time_limit_s))
        assert check_path(grid, robot, result.states, problem.start, problem.goal) == []
        if "mesh_check" in result.extra:
            assert result.extra["mesh_check"]["collides"] is False
    else:
        t0 = time.perf_counter()
        with pytest.raises(NoValidPathFound):
            plan_path(grid, robot, problem.start, problem.goal, termination=Termination(problem.time_limit_s))
        assert time.perf_counter() - t0 < problem.time_limit_s + 1.0


SOLVABLE = [p for p in PROBLEMS if p.solvable]


@pytest.mark.parametrize("problem", SOLVABLE, ids=[f"{p.map}:{p.name}" for p in SOLVABLE])
def test_shipped_problem_with_reversing(problem):
    from planner.hybrid_astar.search import PlannerOptions

    grid = _grid(problem.map_path)
    robot = load_robot()
    result = plan_path(grid, robot, problem.start, problem.goal, PlannerOptions(allow_reverse=True),
                       Termination(problem.time_limit_s))
    assert check_path(grid, robot, result.states, problem.start, problem.goal) == []
