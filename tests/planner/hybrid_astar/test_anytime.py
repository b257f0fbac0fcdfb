"""Anytime planning (issue 21, item 6): ``improve_until_s`` returns the best path found within it, never a dearer one
than the first, and says how it improved. Times are bounded generously (CI is a busy 2-core machine): the checks
are on lengths, costs and the record's structure."""

from __future__ import annotations

import itertools
import json
import math
import time

import pytest

from planner.errors import InvalidInput, PlannerCancelled, PlannerTimedOut
from planner.hybrid_astar.anytime import GREEDS, MAX_IMPROVE_S
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.kinematics import subdivide
from planner.live import live_options
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path
from tests.scenarios import SCENARIO_BINS
from tests.service.service_harness import hall_grid

# the service tests' hall (10 m × 8 m, a wall from the bottom at x = 5 m): the first path from (2, 2) to (8, 2)
# goes round the wall 0.6 m longer than the path the admissible search finds, which finishes in well under a second
# (with 72 heading bins, tests.scenarios: with the default 36 the first path is already the shortest and there is
# nothing to improve)
START, GOAL = (2.0, 2.0, 0.0), (8.0, 2.0, 0.0)
BUDGET_S = 20.0  # far more than the rounds need (≈ 0.2 s on an idle machine): they end by finishing


def hall() -> OccupancyGrid:
    """The service tests' hall (one grid for the cross-door anytime test and these)."""
    return hall_grid()


@pytest.fixture(scope="module")
def grid() -> OccupancyGrid:
    return hall()


@pytest.fixture(scope="module")
def first(grid: OccupancyGrid):
    """The plan with improve_until_s = 0 (its default), at the scenario's 72 heading bins."""
    return HybridAStar(grid, load_robot(), PlannerOptions(n_yaw_bins=SCENARIO_BINS)).plan(START, GOAL, Termination(60))


@pytest.fixture(scope="module")
def improved(grid: OccupancyGrid):
    return HybridAStar(grid, load_robot(), PlannerOptions(improve_until_s=BUDGET_S, n_yaw_bins=SCENARIO_BINS)).plan(
        START, GOAL, Termination(60))


def test_a_long_first_path_gets_shorter_and_stays_valid(grid, first, improved) -> None:
    assert improved.length_m < first.length_m - 0.3  # 10.66 m → 10.01 m measured
    assert check_path(grid, improved.robot, improved.states, START, GOAL) == []
    # the rounds ended by themselves, well within the budget: the greed-0 search found nothing cheaper left
    assert improved.extra["improvement_stop"] == "admissible search finished"
    assert improved.planning_time_s < BUDGET_S


def test_the_record_starts_with_the_first_path_and_only_gets_cheaper(first, improved) -> None:
    rounds = improved.extra["improvements"]
    assert rounds[0]["by"] == "first path"
    # the first entry is the default plan's path: the option changes nothing before the first path is found
    assert rounds[0]["length_m"] == pytest.approx(first.length_m, abs=2e-3)
    assert len(rounds) >= 2
    costs = [r["cost"] for r in rounds]
    assert all(b < a for a, b in itertools.pairwise(costs))
    times = [r["t_s"] for r in rounds]
    assert times == sorted(times) and times[-1] <= improved.planning_time_s
    assert {r["by"] for r in rounds[1:]} <= {f"greed {g:g}" for g in GREEDS} | {"smoothing"}
    assert rounds[-1]["length_m"] == pytest.approx(improved.length_m, abs=2e-3)  # the path returned is the last kept
    assert improved.expansions > first.expansions  # the re-searches' expansions are counted
    assert improved.extra["improvement_expansions"] == improved.expansions - first.expansions
    json.dumps(improved.to_json(), allow_nan=False)  # every door sends it as JSON


def test_the_default_changes_nothing(grid, first) -> None:
    assert PlannerOptions().improve_until_s == 0.0
    assert not {"improvements", "improvement_stop"} & set(first.extra)
    again = HybridAStar(grid, load_robot(), PlannerOptions(improve_until_s=BUDGET_S, n_yaw_bins=SCENARIO_BINS)).plan(
        START, GOAL, Termination(60))
    # the improved plan's first path is the default plan's path, and the default plan stops there
    assert again.extra["improvements"][0]["length_m"] == pytest.approx(first.length_m, abs=2e-3)
    assert again.length_m < first.length_m


def test_never_longer_than_the_first_path_on_several_problems() -> None:
    """Every round's candidate is kept only when it costs less: on a few problems of the search tests' two-walls map
    (with reversing and without) the improved path never costs more than the first one."""
    from tests.planner.hybrid_astar.test_search import two_walls

    grid, robot = two_walls(), load_robot()
    for reverse in (True, False):
        for start, goal in [((2, 2, 0), (18, 18, math.pi / 2)), ((3, 17, -math.pi / 2), (17, 3, 0.0)),
                            ((2, 2, 0), (2.5, 4, math.pi))]:
            result = HybridAStar(grid, robot, PlannerOptions(improve_until_s=0.3, allow_reverse=reverse)).plan(
                start, goal, Termination(30))
            rounds = result.extra["improvements"]
            assert rounds[-1]["cost"] <= rounds[0]["cost"]
            if not reverse:  # forward only, the cost is the length
                assert result.length_m <= rounds[0]["length_m"] + 2e-3
            assert check_path(grid, robot, result.states, start, goal) == []


def test_the_request_time_limit_still_wins(grid) -> None:
    """A limit shorter than improve_until_s ends the rounds with the best path so far, not an error; a limit too
    short for the first path is the usual timeout."""
    from tests.planner.hybrid_astar.test_search import two_walls

    grid2, robot = two_walls(), load_robot()
    # (SLOW_ADMISSIBLE: the greed-0 round cannot end first)
    planner = HybridAStar(grid2, robot, PlannerOptions(improve_until_s=600.0, **SLOW_ADMISSIBLE))
    result = planner.plan((2, 2, 0), (18, 18, math.pi / 2), Termination(1.0))
    assert result.status == "exact"
    assert result.extra["improvement_stop"] == "time limit"
    assert result.planning_time_s < 1.0 + 2.0  # a compiled smoothing pass, once started, finishes
    # (one expansion per chunk: the clock is read before the search can find the path in its first chunk)
    slow = HybridAStar(grid2, robot, PlannerOptions(improve_until_s=600.0, chunk_expansions=1))
    with pytest.raises(PlannerTimedOut):
        slow.plan((2, 2, 0), (18, 18, math.pi / 2), Termination(1e-9))


# Options under which the greed-0 round of two_walls' problem cannot end before the limits below: 72 heading bins
# (the closed set's cells are then the map's), 11 held rolls, each its own closed-set bin. That round takes 22 s on the
# 2-core machine of issue 21's eighteenth round (with the defaults it ended in 1.4 s there, and with 11 rolls at 36
# bins in 3.0 s, once the closed set's cells followed the step); the first path still comes in 5 ms.
SLOW_ADMISSIBLE = {"n_yaw_bins": SCENARIO_BINS, "n_rolls": 11, "n_roll_bins": 0}


def test_improve_until_s_ends_the_rounds() -> None:
    from tests.planner.hybrid_astar.test_search import two_walls

    result = HybridAStar(two_walls(), load_robot(), PlannerOptions(improve_until_s=0.5, **SLOW_ADMISSIBLE)).plan(
        (2, 2, 0), (18, 18, math.pi / 2), Termination(60))
    assert result.extra["improvement_stop"] == "deadline"
    assert result.extra["improve_until_s"] == 0.5
    assert result.planning_time_s < 0.5 + 2.0


def test_a_cancel_is_still_a_cancel() -> None:
    from tests.planner.hybrid_astar.test_search import two_walls

    planner = HybridAStar(two_walls(), load_robot(), PlannerOptions(improve_until_s=600.0, **SLOW_ADMISSIBLE))
    planner.plan((2, 2, 0), (18, 18, math.pi / 2), Termination(2))  # warm: the next plan's first path is quick
    t0 = time.perf_counter()
    with pytest.raises(PlannerCancelled):
        planner.plan((2, 2, 0), (18, 18, math.pi / 2),
                     Termination(60, cancel=lambda: time.perf_counter() - t0 > 0.5))


@pytest.mark.parametrize("value", [-1, -1e-9, math.nan, math.inf, MAX_IMPROVE_S * 2, "x", True, None, [1]])
def test_bad_values_are_refused_by_name(value) -> None:
    with pytest.raises(InvalidInput) as err:
        PlannerOptions.from_dict({"improve_until_s": value})
    assert err.value.field == "options.improve_until_s"


def test_live_sessions_do_not_improve_unless_asked() -> None:
    assert live_options().improve_until_s == 0.0
    assert live_options({"improve_until_s": 0.2}).improve_until_s == 0.2


def test_subdivide_keeps_the_motions() -> None:
    motions = [(0.1, 0.5, 1.0), (0.0, 0.0, -0.25), (0.2, 0.0, 0.0)]
    pieces = subdivide(motions, 0.3)
    assert len(pieces) == 4 + 1 + 1
    assert sum(s for _, _, s in pieces) == pytest.approx(sum(s for _, _, s in motions))
    assert all(abs(s) <= 0.3 + 1e-12 for _, _, s in pieces)


def test_a_budget_shares_the_preprocessed_planner(grid) -> None:
    """planner_for: improve_until_s does not change the map's preprocessing, so the cached planner is shared."""
    from planner.hybrid_astar.plan import planner_for

    robot = load_robot()
    plain = planner_for(grid, robot, PlannerOptions())
    budgeted = planner_for(grid, robot, PlannerOptions(improve_until_s=1.5))
    assert budgeted.clearance is plain.clearance and budgeted.holonomic_mult is plain.holonomic_mult
    assert budgeted.options.improve_until_s == 1.5 and plain.options.improve_until_s == 0.0
    assert planner_for(grid, robot, PlannerOptions()) is plain


def test_a_round_takes_the_shot_it_held_back_when_that_costs_less() -> None:
    """bays#1 of the real bench's seed-0 draw: the greed-0.5 round finds a path while a mostly-backwards shot it held
    back costs less, both smoothed (cost 21.91 against the first path's 22.88, measured); the round's path is that
    shot, as the first path is chosen (``HybridAStar._held_if_cheaper``), and the record says so. (The round ends
    within 0.1 s on an idle machine; the 2 s budget leaves it twenty times that.)"""
    from planner.maps.load import load_map

    grid, robot = load_map("maps/real/bays.yaml"), load_robot()
    start, goal = (11.975, 3.625, -0.4698024057459014), (22.075, 9.475, -0.2510437936434946)
    result = HybridAStar(grid, robot, PlannerOptions(improve_until_s=2.0)).plan(start, goal, Termination(60))
    rounds = result.extra["improvements"]
    held = [r for r in rounds if r["by"] == "greed 0.5, held shot"]
    assert held and held[0]["cost"] < rounds[0]["cost"]
    assert check_path(grid, robot, result.states, start, goal) == []
