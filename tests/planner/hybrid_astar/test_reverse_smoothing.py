"""Reversing paths are smoothed like forward ones, and a path that rolls most of its length backwards is
replaced by a forward one when that costs less (the README's garage U-turn)."""

import dataclasses
import math

import numpy as np
import pytest

from planner.hybrid_astar import kernels, smoothing
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.kinematics import child_pose
from planner.maps.load import load_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.pathcheck import check_path
from tests.scenarios import SCENARIO_BINS  # scenarios found with 72 heading bins keep them

ROBOT = load_robot("zju-60")
# a sphere with a sensor boom 0.9 m ahead: not symmetric under a half turn, so a reverse stretch checked with
# the footprint facing the wrong way would be checked against the wrong shape
BOOM = dataclasses.replace(ROBOT, footprint=((0.9, 0.0), (0.3, 0.3), (-0.3, 0.3), (-0.3, -0.3), (0.3, -0.3)))
START, GOAL = (12.0, 8.05, 0.0), (12.0, 23.55, math.pi)  # the README's garage U-turn


@pytest.fixture(scope="module")
def garage():
    return load_map("maps/garage.yaml")


def _backwards_m(states: np.ndarray) -> float:
    ds = np.diff(states[:, 6])
    return float(ds[states[1:, 4] < 0].sum())


def _roll_sign_changes(states: np.ndarray) -> int:
    signs = np.sign(np.round(states[:, 3], 3))
    signs = signs[signs != 0]
    return int((np.diff(signs) != 0).sum())


def _cost(states: np.ndarray, o: PlannerOptions) -> float:
    """Length + (reverse_penalty − 1) × metres backwards + switch_cost per cusp, from the states alone."""
    d = np.sign(states[1:, 4])
    d = d[d != 0]
    cusps = int((np.diff(d) != 0).sum())
    return float(states[-1, 6]) + (o.reverse_penalty - 1.0) * _backwards_m(states) + o.switch_cost_m * cusps


@pytest.mark.parametrize("robot", [ROBOT, BOOM], ids=["zju-60", "boom"])
def test_a_path_rolled_backwards_is_smoothed(garage, robot) -> None:
    # one step per expansion everywhere: the raw path zig-zags between held rolls, which the smoother must undo
    # (long steps in the open make the raw path straighter to begin with)
    options = PlannerOptions(prefer_forward=False, open_step_factor=1)
    result = HybridAStar(garage, robot, options).plan(START, GOAL)
    states = result.states
    assert _backwards_m(states) > 0.8 * result.length_m  # the search rolls this U-turn backwards
    assert check_path(garage, robot, states, START, GOAL) == []
    # the search's zig-zag of held rolls is shortcut: before, the reverse stretch kept it (29.1 m, 62 changes). (Since
    # prefer_forward off holds no shot back, the raw path ends in the search's first backwards shot: 26.4 m → 23.9 m
    # for the boom, 27.3 → 23.3 m when the search went on for 614 expansions.)
    assert result.length_m < 0.92 * result.extra["unsmoothed_length_m"]
    assert _roll_sign_changes(states) <= 12


def test_mirroring_a_reverse_motion_is_the_same_motion() -> None:
    """(yaw, φ, κ, s) → (yaw + π, −φ, −κ, −s) moves the centre the same way (what reverse smoothing relies on)."""
    rng = np.random.default_rng(4)
    for _ in range(200):
        x, y, yaw, r0, r1 = rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-4, 4), *rng.uniform(-0.3, 0.3, 2)
        k, s = ROBOT.roll_model.curvature(r1), -rng.uniform(0, 2)
        a = child_pose(x, y, yaw, r0, r1, k, ROBOT.radius_m, s)
        b = child_pose(x, y, yaw + math.pi, -r0, -r1, -k, ROBOT.radius_m, -s)
        assert a[0] == pytest.approx(b[0], abs=1e-9) and a[1] == pytest.approx(b[1], abs=1e-9)
        assert math.remainder(b[2] - a[2] - math.pi, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_the_mirrored_footprint_is_the_footprint_turned_round(garage) -> None:
    planner = HybridAStar(garage, BOOM)
    rng = np.random.default_rng(7)
    p = planner._params(GOAL, True)
    clear, blocked = planner.clearance.clearance, planner.clearance.blocked
    differs = 0
    for _ in range(300):
        x, y, yaw = rng.uniform(1, 39), rng.uniform(1, 29), rng.uniform(-math.pi, math.pi)
        own = kernels._pose_margin(clear, blocked, p, *planner._footprint_arrays(), x, y, yaw)
        turned = kernels._pose_margin(clear, blocked, p, *smoothing.turned_round(*planner._footprint_arrays()), x, y,
                                      yaw + math.pi)
        assert turned == pytest.approx(own, abs=1e-9)
        unturned = kernels._pose_margin(clear, blocked, p, *planner._footprint_arrays(), x, y, yaw + math.pi)
        differs += abs(unturned - own) > 0.01
    # (a motion of length 0 samples no pose: until issue 21's thirteenth round this test compared two margins of
    # such motions, both infinite, and could not fail)
    assert differs > 50  # the boom faces the other way: the footprint not turned round is another shape


def test_a_mostly_backwards_path_gives_way_to_a_cheaper_forward_one(garage) -> None:
    o = PlannerOptions()
    backwards = HybridAStar(garage, ROBOT, PlannerOptions(prefer_forward=False)).plan(START, GOAL)
    result = HybridAStar(garage, ROBOT, o).plan(START, GOAL)
    assert result.extra.get("forward_alternative") is True
    assert _backwards_m(result.states) < 0.5 * result.length_m
    assert check_path(garage, ROBOT, result.states, START, GOAL) == []
    assert _cost(result.states, o) < _cost(backwards.states, o)
    assert result.expansions > backwards.expansions  # the forward search's expansions are counted too


def test_a_path_that_must_back_out_is_left_alone() -> None:
    """A back-out of a dead end is not a reason for a second search. (The search backs out and turns round. Until
    issue 21's ninth round the shot held back meanwhile, backwards nearly all the way and then a turn, was the path:
    9.94 m at cost 12.51 against 10.66 m and 12.72. Now a free shot that keeps less than the preferred clearance in
    the 1.2 m bay is found first and taken 400 expansions on, none keeping it: 9.94 m too, 4.1 m of it backwards.)"""
    occ = np.zeros((80, 240), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[:28, 160:] = True  # a 1.2 m wide dead-end bay from x = 8 m to the east wall
    occ[52:, 160:] = True
    grid = OccupancyGrid.from_occupied(occ, 0.05, name="bay")
    start, goal = (10.5, 2.0, 0.0), (2.0, 2.0, math.pi)
    result = HybridAStar(grid, ROBOT, PlannerOptions(n_yaw_bins=SCENARIO_BINS)).plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert _backwards_m(result.states) > 0.0 and result.extra["fallback_shot_taken"]
    assert "forward_alternative_expansions" not in result.extra


def test_a_goal_that_cannot_be_approached_forwards_ends_the_forward_search_at_once() -> None:
    """pockets#8 of the real-map bench: the path rolls mostly backwards and a forward path could be cheaper by the
    Dubins bound, but the goal sits in a pocket that a forward-only search from the goal exhausts in a few states:
    no forward path exists. The forward-only search's goal side (rolling forwards from the goal) runs dry in those
    few states (fewer still below the first path's cost), after one turn of the start's side (up to 20 000
    expansions before the goal check, issue 21's sixth round)."""
    from planner.hybrid_astar.dubins import dubins_distance
    from planner.hybrid_astar.search import FORWARD_CHECK_BUDGET, FORWARD_SLICE
    from planner.termination import Termination

    grid = load_map("maps/real/pockets.yaml")
    start, goal = (26.875, 14.625, -2.1864988338850018), (4.825, 17.325, -1.1774962766354187)
    o = PlannerOptions(n_yaw_bins=SCENARIO_BINS)
    planner = HybridAStar(grid, ROBOT, o)
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert _backwards_m(result.states) > 0.5 * result.length_m  # the forward alternative's trigger ...
    assert dubins_distance(*start, *goal, ROBOT.min_turning_radius_m) < _cost(result.states, o)  # ... both parts
    exhausted = planner._reverse_search(start, goal, o, Termination(10).start(), reverse=False,
                                        budget=FORWARD_CHECK_BUDGET)
    assert exhausted is not None and exhausted < 100
    assert "forward_alternative" not in result.extra
    assert 0 < result.extra["forward_check_expansions"] <= exhausted  # counted in the result's expansions
    assert result.extra["forward_alternative_expansions"] <= FORWARD_SLICE
    # the garage's goal can be approached forwards: there the forward search still runs and wins (test above)
    assert HybridAStar(load_map("maps/garage.yaml"), ROBOT, o)._reverse_search(
        START, GOAL, o, Termination(10).start(), reverse=False, budget=FORWARD_CHECK_BUDGET) is None


def test_the_forward_check_budget_still_proves_the_deepest_dead_end_seen() -> None:
    """pockets#8 of the real-map bench's seed-1 draw: the deepest goal pocket over seeds 0–5 (360 problems) whose
    forward-only check exhausts, after 516 expansions (the next ones 497 and 348; one more at 833 is given up). The
    check's budget was cut from 1 000 (it runs to its budget on every plan whose goal can be approached forwards: 68
    of those 360 plans) but still proves this one."""
    from planner.hybrid_astar.search import FORWARD_CHECK_BUDGET
    from planner.termination import Termination

    grid = load_map("maps/real/pockets.yaml")
    start, goal = (8.925, 3.525, 2.0387814393209416), (6.975, 17.375, 1.7503720758899775)
    o = PlannerOptions(n_yaw_bins=SCENARIO_BINS)
    planner = HybridAStar(grid, ROBOT, o)
    exhausted = planner._reverse_search(start, goal, o, Termination(10).start(), reverse=False,
                                        budget=FORWARD_CHECK_BUDGET)
    assert exhausted is not None and 500 < exhausted <= FORWARD_CHECK_BUDGET
    # Since issue 21's eighteenth round the goal side is part of the forward search, and both prune what costs more
    # than the first path: here the start's side runs out of such states first, in 24 expansions.
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert "forward_alternative" not in result.extra
    assert result.extra["forward_alternative_expansions"] + result.extra["forward_check_expansions"] < 100


def test_the_forward_search_gets_a_budget_by_distance() -> None:
    """smoothers_world#8 of the real-map bench (seed 0): the path rolls mostly backwards, a forward-only goal check
    does not exhaust, and no cheaper forward path exists within reach. The forward search is given 250
    expansions per metre of the 3.6 m between start and goal, at least 1 000; it ran the flat 20 000 before
    (150–250 ms), then 3 000. On the open field a longer problem gets more (the accepted forward paths of 480 drawn
    problems needed 7–241 per metre but for one at 371 and three that no budget up to 20 000 reached,
    docs/planning.md)."""
    from planner.hybrid_astar.search import FORWARD_RETRY_MAX, FORWARD_RETRY_MIN

    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (0.6, 0.8, 1.0)) == FORWARD_RETRY_MIN == 1_000
    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (60.0, 80.0, 1.0)) == 20_000 == FORWARD_RETRY_MAX
    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (12.0, 16.0, 1.0)) == 5_000
    # ... and at most three times the expansions the plan made before it, below the floor too (issue 21's eleventh
    # round: a plan found in 57 expansions ran a forward search of 1 000 that found nothing, depot#1 of seed 0)
    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (60.0, 80.0, 1.0), spent=1_800) == 5_400
    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (12.0, 16.0, 1.0), spent=10_000) == 5_000
    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (12.0, 16.0, 1.0), spent=100) == 300
    assert HybridAStar.forward_budget((0.0, 0.0, 0.0), (0.6, 0.8, 1.0), spent=1_000) == FORWARD_RETRY_MIN
    grid = load_map("maps/real/smoothers_world.yaml")
    start, goal = (9.275, 5.325, -0.9024881717968012), (7.875, 2.025, -1.7184486953680036)
    result = HybridAStar(grid, ROBOT).plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert _backwards_m(result.states) > 0.5 * result.length_m
    assert "forward_alternative" not in result.extra
    assert 0 < result.extra["forward_alternative_expansions"] <= FORWARD_RETRY_MIN


@pytest.mark.parametrize("bins", [36, 72])
def test_the_expansion_budgets_follow_the_heading_bins(bins) -> None:
    """The budgets counted in expansions were measured at search.BUDGET_BINS (72) heading bins; the step follows the
    bin, so a search at 36 bins, whose expansions roll twice as far, gets half of each (issue 21's thirteenth round):
    the same metres of search. smoothers_world#8 of seed 0 (above) runs its forward alternative to the budget."""
    from planner.hybrid_astar import kernels
    from planner.hybrid_astar.search import (
        BUDGET_BINS,
        FORWARD_CHECK_BUDGET,
        FORWARD_RETRY_MIN,
        HOLD_EXPANSIONS,
        MEET_AFTER,
    )

    grid = load_map("maps/real/smoothers_world.yaml")
    start, goal = (9.275, 5.325, -0.9024881717968012), (7.875, 2.025, -1.7184486953680036)
    planner = HybridAStar(grid, ROBOT, PlannerOptions(n_yaw_bins=bins))
    share = bins / BUDGET_BINS
    assert planner.budget(MEET_AFTER) == MEET_AFTER * share and planner.budget(0) == 0
    assert planner._params(goal, True)[kernels.P_HOLD_WAIT] == HOLD_EXPANSIONS * share
    assert HybridAStar.forward_budget(start, goal, 0, planner.budget_scale) == FORWARD_RETRY_MIN * share
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    spent = result.extra["forward_alternative_expansions"] + result.extra["forward_check_expansions"]
    assert spent == (FORWARD_RETRY_MIN + FORWARD_CHECK_BUDGET) * share  # the two sides' budget, shared


def test_a_plan_found_quickly_spends_little_on_the_forward_alternative() -> None:
    """depot#1 of the real-map bench's seed 0: the search holds back a shot that rolls mostly backwards and takes it
    after 57 expansions. The forward-only alternative then gets 3 × those (171), not the floor of 1 000 that found
    nothing cheaper, and its goal side the forward check's 300 more (at 36 heading bins) between them (before issue
    21's eleventh round: 57 + 600 + 1 000 expansions, 18 × BIT*'s first solution; 228 until the eighteenth round
    made the goal side part of the forward search, 456 since)."""
    from planner.hybrid_astar.search import FORWARD_CHECK_BUDGET, FORWARD_RETRY_TIMES

    grid = load_map("maps/real/depot.yaml")
    start, goal = (26.025, 9.575, 0.06727095832306862), (10.625, 9.575, 3.1096574102329626)
    planner = HybridAStar(grid, ROBOT)
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert result.extra.get("held_shot_taken")
    forward = result.extra["forward_alternative_expansions"] + result.extra["forward_check_expansions"]
    searched = result.expansions - forward
    assert 0 < forward <= FORWARD_RETRY_TIMES * searched + planner.budget(FORWARD_CHECK_BUDGET)
    assert FORWARD_RETRY_TIMES * searched <= FORWARD_CHECK_BUDGET
    assert result.expansions < 500


def test_the_forward_search_ends_at_once_when_nothing_forwards_is_cheaper() -> None:
    """smoothers_world#9 of the real-map bench's seed 0: the forward alternative may take 1 000 expansions, but its
    start's side runs out of states that cost less than the first path in two (until issue 21's eleventh round a
    forward check of 600 ran first; it proved this goal's pocket in 195 expansions)."""
    grid = load_map("maps/real/smoothers_world.yaml")
    start, goal = (11.225, 4.375, -2.0729579111761445), (9.825, 1.125, 1.6366855694506848)
    result = HybridAStar(grid, ROBOT).plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert 0 < result.extra["forward_alternative_expansions"] + result.extra["forward_check_expansions"] < 50
    assert "forward_alternative" not in result.extra


def test_a_forward_search_that_ends_in_its_first_turn_sets_up_no_goal_side(monkeypatch) -> None:
    """The same problem: the forward search's start's side runs dry within its first FORWARD_SLICE expansions, so its
    goal side (a holonomic wavefront of its own and a search) is never set up; nineteenth round of issue 21: 0.5–1.7
    ms a plan on the 100 m field and the warehouse, where the forward path is found in tens of expansions."""
    from planner.hybrid_astar import search

    made: list[bool] = []

    class Counted(search.GoalSide):
        def __init__(self, *args, reverse=None, **kwargs):  # type: ignore[no-untyped-def]
            made.append(reverse is False)
            super().__init__(*args, reverse=reverse, **kwargs)

    monkeypatch.setattr(search, "GoalSide", Counted)
    grid = load_map("maps/real/smoothers_world.yaml")
    start, goal = (11.225, 4.375, -2.0729579111761445), (9.825, 1.125, 1.6366855694506848)
    result = HybridAStar(grid, ROBOT).plan(start, goal)
    assert result.extra["forward_alternative_expansions"] < search.FORWARD_SLICE
    assert result.extra["forward_check_expansions"] == 0 and not any(made)


def test_a_forward_path_found_from_the_goal_replaces_one_rolling_backwards() -> None:
    """100by100_20#7 of the real-map bench's seed 1: the start faces away from the goal, 40 m off, and a round
    obstacle lies where the cheapest turn would go. The plan rolls 42 m backwards (cost 50.9 by the planner's own
    measure); a forward path costs 48.3. The forward-only search from the start alone spent its 3 000 expansions
    beside that obstacle; its goal side, searched in turns with it since issue 21's eighteenth round, finds the
    path, and the plan rolls forwards."""
    grid = load_map("maps/real/100by100_20.yaml")
    start, goal = (46.325, 83.475, -2.7498386939664643), (62.725, 46.125, 2.2156574695706945)
    o = PlannerOptions()
    planner = HybridAStar(grid, ROBOT, o)
    backwards = HybridAStar(grid, ROBOT, PlannerOptions(prefer_forward=False)).plan(start, goal)
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert _backwards_m(backwards.states) > 0.9 * backwards.length_m
    assert result.extra.get("forward_alternative") is True and _backwards_m(result.states) == 0.0
    assert _cost(result.states, o) < _cost(backwards.states, o) - 1.0
    assert result.extra["forward_check_expansions"] > 0
    assert result.min_clearance_m >= ROBOT.preferred_clearance_m


def test_a_forward_path_that_grazes_an_obstacle_does_not_replace_a_roomy_one(monkeypatch) -> None:
    """100by100_20#7 of the real-map bench's seed 2: the forward-only search finds a forward path that costs less
    (68.95 m against 69.16 m rolled backwards, both × the reverse penalty) by joining its two sides with a shot
    that passes 1.4 cm from an obstacle (meet.py's joins keep no room). The backwards path keeps 0.39 m: the
    forward path is taken only when it keeps as much, or LEAST_KEPT_MARGIN_M."""
    from planner.hybrid_astar import search

    grid = load_map("maps/real/100by100_20.yaml")
    start, goal = (85.775, 29.075, 2.1060181869358994), (41.625, 75.725, -1.909020745000034)
    result = HybridAStar(grid, ROBOT).plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert "forward_alternative" not in result.extra and result.extra["forward_check_expansions"] > 0
    assert _backwards_m(result.states) > 0.9 * result.length_m
    assert result.min_clearance_m >= ROBOT.preferred_clearance_m
    # without the room rule the grazing forward path is the plan
    monkeypatch.setattr(search.HybridAStar, "_least_margin", lambda self, start, motions: 1.0)
    grazing = HybridAStar(grid, ROBOT).plan(start, goal)
    assert grazing.extra.get("forward_alternative") is True
    assert grazing.min_clearance_m < 0.05


def test_a_manoeuvre_in_a_path_that_rolls_backwards_is_shortcut_with_a_reverse_shot() -> None:
    """A join of the two-ended search (meet.py) can bring a manoeuvre into a path that rolls backwards: back up, a
    bit forwards on the other lock, back up again. The stretches of one direction are shortcut one by one and a
    forward shot cannot replace it (the sphere faces the other way), so before issue 21's tenth round the cusps
    stayed (pockets#9 of the real-map bench's seed 0: a loop of 1.3 m in a 1.7 m corridor). A reverse shot across
    the whole path replaces it when it is shorter."""
    grid = OccupancyGrid.from_occupied(np.zeros((300, 300), dtype=bool), 0.05, name="open")
    planner = HybridAStar(grid, ROBOT)
    roll = ROBOT.max_roll_rad
    kappa = float(ROBOT.roll_model.curvature(roll))
    start = (10.0, 7.5, 0.0)
    shuffle = [(0.0, 0.0, -1.0), (roll, kappa, -0.6), (-roll, -kappa, 0.6), (0.0, 0.0, -1.0), (0.0, 0.0, 0.0)]
    p = planner._params((0.0, 0.0, 0.0), True)
    out = planner._shortcut(start, shuffle, p, 24)
    assert sum(1 for m in shuffle if m[2] > 0) == 1 and all(s <= 0 for _, _, s in out)  # no cusp left
    assert planner._length(start, out) < 0.7 * planner._length(start, shuffle)  # 3.51 → 2.10 m
    end, want = planner._knots(start, out)[-1], planner._knots(start, shuffle)[-1]
    assert np.allclose(end[:4], want[:4], atol=1e-5)  # the same pose and roll at the end


def test_prefer_forward_off_takes_the_path_as_the_search_finds_it() -> None:
    """depot#20 of the real bench's seed-0 draw at 40 a map: the goal 23 m behind. By default the search holds back
    its shot that rolls mostly backwards and looks for a path that turns round (kernels 3c); here it finds a dearer
    one, so the held shot is the path after 603 expansions. With ``prefer_forward`` off nothing is held and no
    forward-only search runs: the same path in 25 (issue 21's twenty-second round: the option switches off the
    whole forward preference, not only the forward-only search)."""
    grid = load_map("maps/real/depot.yaml")
    start, goal = (1.725, 7.575, 3.060120748362473), (24.225, 8.975, -2.3643296132075022)
    held = HybridAStar(grid, ROBOT).plan(start, goal)
    free = HybridAStar(grid, ROBOT, PlannerOptions(prefer_forward=False)).plan(start, goal)
    for result in (held, free):
        assert check_path(grid, ROBOT, result.states, start, goal) == []
        assert _backwards_m(result.states) > 0.9 * result.length_m
    assert held.extra.get("held_shot_taken") is True
    assert not {"held_shot_taken", "fallback_shot_taken", "forward_alternative_expansions"} & set(free.extra)
    assert free.expansions * 10 < held.expansions
    assert free.length_m == pytest.approx(held.length_m, abs=1e-3)
