"""The smoother's shortcut kernel can skip most of the shots that failed from the knot before (kernels.shortcut,
``recheck``; off by default since it made an explore world collide, search.SMOOTH_RECHECK): with it, it must
build far fewer shots than trying every candidate from every knot, and its path may be at most 1 % longer than
that exhaustive smoothing's (skipped candidates can hold a slightly better shortcut; on the 60 real-map problems
of seed 0, measured when the rule was made, no path was more than 0.2 % longer and the total 0.26 % shorter)."""

import math

import numpy as np
import pytest

from planner.hybrid_astar import search
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.maps.load import load_map
from planner.robot import load_robot
from tests.pathcheck import check_path

ROBOT = load_robot()
PROBLEMS = {  # map, start, goal
    "garage": ("maps/garage.yaml", (12.0, 8.05, 0.0), (12.0, 23.55, math.pi)),  # the README's garage U-turn
    # issue 21's real-map problems (bench --suite real, seed 0) whose smoothing cost most
    "bays#4": ("maps/real/bays.yaml", (1.725, 10.775, 1.4577), (21.625, 13.725, -2.7264)),
    "warehouse#0": ("maps/real/warehouse.yaml", (5.255, 11.615, 0.5371), (-1.015, 3.965, -1.3398)),
}


class _Counting(HybridAStar):
    """Adds up kernels.shortcut's counts over every smoothing of a plan."""

    counts: np.ndarray

    def _smooth(self, start, motions, p, o, counts=None):  # type: ignore[no-untyped-def]
        return super()._smooth(start, motions, p, o, self.counts)


def _plan(name: str) -> tuple[float, np.ndarray]:
    path, start, goal = PROBLEMS[name]
    grid = load_map(path)
    planner = _Counting(grid, ROBOT, PlannerOptions())
    planner.counts = np.zeros(4, dtype=np.int64)
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    return result.length_m, planner.counts


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_smoothing_skips_shots_without_lengthening_the_path(name, monkeypatch) -> None:
    every_length, every = _plan(name)  # the default: every candidate from every knot
    assert every[2] == 0
    monkeypatch.setattr(search, "SMOOTH_RECHECK", 3)  # the recheck rule (off by default, see search.py)
    monkeypatch.setattr(search, "SMOOTH_RECHECK_FIRST", 2)
    length, counts = _plan(name)
    assert counts[2] > 0
    assert counts[0] < 0.6 * every[0]
    assert length <= 1.01 * every_length
