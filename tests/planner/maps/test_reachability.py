"""The inscribed-disc flood fill that refuses unreachable goals before the search (planner.maps.reachability).

It must never refuse a goal the search can reach: checked here against the search itself on every shipped
problem and on seeded real-map problems (the search run with the refusal switched off).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import NoValidPathFound, PlannerTimedOut
from planner.hybrid_astar import search
from planner.hybrid_astar.plan import plan_path, planner_for
from planner.hybrid_astar.search import HybridAStar
from planner.maps.clearance import ClearanceMap, clearance_cells, edt_cells
from planner.maps.nav2 import load_map
from planner.maps.problems import list_problems
from planner.maps.reachability import components, goal_reachable
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination

ROBOT = load_robot("zju-60")


def _wall(gap_m: float) -> OccupancyGrid:
    """A 12 m × 6 m room split by a wall at x = 5.9–6.1 m with a gap of ``gap_m`` in its middle (0: none)."""
    occ = np.zeros((120, 240), dtype=bool)
    occ[:, 118:122] = True
    if gap_m > 0:
        g0 = round((3.0 - gap_m / 2) / 0.05)
        occ[g0:g0 + round(gap_m / 0.05), 118:122] = False
    return OccupancyGrid.from_occupied(occ, 0.05, name=f"wall-{gap_m:g}")


def test_a_goal_behind_a_gap_narrower_than_the_footprint_is_refused_before_any_expansion() -> None:
    grid = _wall(0.40)  # the footprint's inscribed disc is 0.64 m across
    with pytest.raises(NoValidPathFound) as err:
        plan_path(grid, ROBOT, (2.0, 3.0, 0.0), (10.0, 3.0, 0.0), termination=Termination(30.0))
    assert err.value.code == 208 and err.value.expansions == 0
    assert "cannot reach" in err.value.msg and "0.64 m disc" in err.value.msg
    # on the same side of the wall the goal is planned as before
    result = plan_path(grid, ROBOT, (2.0, 3.0, 0.0), (4.5, 4.5, 1.0), termination=Termination(30.0))
    assert result.status == "exact"


def test_a_gap_the_footprint_fits_through_is_not_refused() -> None:
    grid = _wall(1.5)
    result = plan_path(grid, ROBOT, (2.0, 3.0, 0.0), (10.0, 3.0, 0.0), termination=Termination(30.0))
    assert result.status == "exact" and result.length_m >= 8.0 - 1e-6  # straight through the gap


def test_goal_tolerance_counts() -> None:
    """A goal whose own cell is cut off but that the search may end near (within its tolerance) is let through."""
    grid = _wall(0.0)
    cm = ClearanceMap(grid)
    poly = ROBOT.footprint_polygon
    start, goal = (2.0, 3.0, 0.0), (10.0, 3.0, 0.0)
    assert not goal_reachable(cm, poly, start, goal, 0.1)
    assert goal_reachable(cm, poly, start, goal, 8.0)  # the start's side lies within 8 m of the goal


def test_labels_follow_a_map_changed_in_place() -> None:
    """A live map rewrites its planner's blocked cells and clearance in place: the cached labels must not be
    trusted stale (a goal behind a wall that was opened becomes reachable, and closing it refuses again)."""
    grid = _wall(0.0)
    cm = ClearanceMap(grid)
    poly = ROBOT.footprint_polygon
    start, goal = (2.0, 3.0, 0.0), (10.0, 3.0, 0.0)
    assert not goal_reachable(cm, poly, start, goal, 0.1)
    before = components(cm, 0.32)
    assert components(cm, 0.32) is before  # unchanged: the labels are not computed again
    cm.write_blocked((slice(40, 80), slice(118, 122)), np.zeros((40, 4), bool))  # a 2 m opening, as refresh writes
    cm.clearance[...] = clearance_cells(cm.blocked, 0.05)
    assert goal_reachable(cm, poly, start, goal, 0.1)
    assert components(cm, 0.32) is not before
    cm.write_blocked((slice(40, 80), slice(118, 122)), np.ones((40, 4), bool))
    cm.clearance[...] = clearance_cells(cm.blocked, 0.05)
    assert not goal_reachable(cm, poly, start, goal, 0.1)


def test_clearance_cells_is_the_scaled_distance_transform() -> None:
    rng = np.random.default_rng(3)
    blocked = rng.random((90, 130)) < 0.05
    expected = edt_cells(blocked) * 0.05 - math.sqrt(2.0) * 0.05
    assert np.array_equal(clearance_cells(blocked, 0.05), expected)


def _search_without_refusal(monkeypatch: pytest.MonkeyPatch, planner: HybridAStar, start: tuple[float, float, float],
                            goal: tuple[float, float, float], limit_s: float) -> bool:
    """Does the search itself (the refusal switched off) find a path within ``limit_s``?"""
    with monkeypatch.context() as m:
        m.setattr(search, "refuse_unreachable", lambda *args, **kwargs: None)
        try:
            planner.plan(start, goal, Termination(limit_s))
        except (NoValidPathFound, PlannerTimedOut):
            return False
    return True


def test_the_shipped_problems_refused_are_exactly_the_unsolvable_ones_and_the_search_agrees(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Every solvable shipped problem is accepted and solved with the check on; every refused one is also
    unsolved by the search without the check (so the check only says sooner what the search finds)."""
    problems = list_problems()
    refused = 0
    for p in problems:
        grid = load_map(p.map_path)
        planner = planner_for(grid, ROBOT)
        ok = goal_reachable(planner.clearance, planner.polygon, p.start, p.goal, planner.options.goal_tolerance_m)
        if p.solvable:
            assert ok, p.name
            assert plan_path(grid, ROBOT, p.start, p.goal, termination=Termination(p.time_limit_s)).status == "exact"
        if not ok:
            refused += 1
            assert not _search_without_refusal(monkeypatch, planner, p.start, p.goal, min(p.time_limit_s, 3.0)), p.name
    assert refused == sum(not p.solvable for p in problems)  # all ten shipped unsolvable goals are disconnected


@pytest.mark.parametrize(("name", "n", "seed", "unreachable"), [
    ("pockets", 3, 2, 1), ("bays", 3, 4, 1), ("depot", 3, 3, 1), ("smoothers_world", 3, 3, 0)])
def test_real_map_problems_the_search_solves_are_never_refused(
        monkeypatch: pytest.MonkeyPatch, name: str, n: int, seed: int, unreachable: int) -> None:
    """Seeded draws that include a goal in a sealed pocket or bay: refused exactly where the bench's own
    proof (on the lab referee's grid) says unreachable, and never where the search finds a path."""
    from lab.planning.real.problems import draw_problems, resolve_map

    grid = load_map(resolve_map(name))
    planner = planner_for(grid, ROBOT)
    refused = 0
    for p in draw_problems(grid, ROBOT, n, np.random.default_rng(seed)):
        ok = goal_reachable(planner.clearance, planner.polygon, p.start, p.goal, planner.options.goal_tolerance_m)
        assert ok == (not p.disconnected), p.name
        solved = _search_without_refusal(monkeypatch, planner, p.start, p.goal, 3.0)
        assert ok or not solved, p.name
        if not ok:
            refused += 1
            with pytest.raises(NoValidPathFound, match="cannot reach"):
                plan_path(grid, ROBOT, p.start, p.goal, termination=Termination(3.0))
    assert refused == unreachable
