"""Meet in the middle (planner/hybrid_astar/meet.py): the bucket look-up pairs a forward node with a goal-side node
of nearly the same pose (the goal side's heading turned by π, upright only), and a problem with a manoeuvre at both
ends that the two-ended search alone needs 220 k expansions for is joined within a few tens of thousands."""

import itertools
import math

import numpy as np
import pytest

from planner.errors import NoValidPathFound, PlannerCancelled
from planner.hybrid_astar import search, two_ended
from planner.hybrid_astar.meet import CELL_M, YAW_BINS, Buckets, find_pairs, find_turn
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.maps.nav2 import load_map
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path
from tests.scenarios import SCENARIO_BINS  # scenarios found with 72 heading bins keep them

ROBOT = load_robot("zju-60")
SCENARIO = PlannerOptions(n_yaw_bins=SCENARIO_BINS)
UPRIGHT = 3  # roll index of the upright roll among 7


def _nodes(rows):
    """node_f (x, y, yaw, roll, g) and node_i (parent, roll index, direction) from (x, y, yaw, roll index, g)."""
    node_f = np.array([(x, y, yaw, 0.0, g) for x, y, yaw, _, g in rows], float)
    node_i = np.array([(-1, ri, 1) for *_, ri, _ in rows], dtype=np.int64)
    return node_f, node_i


def _index(tree, turn, upright):
    """The buckets of a tree (node_f, node_i) on a 20 m × 20 m map, headings turned by ``turn``."""
    buckets = Buckets(4)
    buckets.add(tree[0], tree[1], 0, len(tree[0]), turn, upright, GEO)
    return buckets


GEO = (0.0, 0.0, CELL_M, 40, 40, YAW_BINS)  # a 20 m × 20 m map


def _pairs(forward, back):
    b = _index(back, math.pi, UPRIGHT)
    out_a, out_b, out_cost = np.zeros(8, np.int64), np.zeros(8, np.int64), np.zeros(8)
    n = find_pairs(forward[0], forward[1], 0, len(forward[0]), 0.0, -1, back[0], math.pi, b.keys, b.nodes, *GEO, 1.0,
                   10.0, out_a, out_b, out_cost)
    return sorted((int(out_a[m]), int(out_b[m]), float(out_cost[m])) for m in range(n))


def test_a_forward_node_is_paired_with_the_cheapest_upright_goal_side_node_of_its_pose_turned_by_pi():
    forward = _nodes([(5.1, 5.1, 0.3, 2, 1.0), (15.0, 15.0, 0.3, UPRIGHT, 1.0)])
    back = _nodes([
        (5.2, 5.0, 0.3 + math.pi, UPRIGHT, 4.0),   # the same pose in the forward frame: paired
        (5.3, 5.2, 0.3 + math.pi, UPRIGHT, 2.0),   # same bucket, cheaper: kept instead of the first
        (5.1, 5.1, 0.3 + math.pi, 1, 0.5),         # not upright: never used
        (5.1, 5.1, 0.3, UPRIGHT, 0.5),             # heading not turned: faces the other way in the forward frame
    ])
    pairs = _pairs(forward, back)
    assert [(a, b) for a, b, _ in pairs] == [(0, 1)]
    a, b, cost = pairs[0]
    assert cost == pytest.approx(1.0 + 2.0 + math.hypot(0.2, 0.1))


def test_a_node_in_the_next_cell_is_paired_and_one_two_cells_away_is_not():
    forward = _nodes([(5.45, 5.25, 0.0, UPRIGHT, 0.0)])
    near = _nodes([(5.55, 5.25, math.pi, UPRIGHT, 0.0)])   # the cell to the right
    far = _nodes([(6.55, 5.25, math.pi, UPRIGHT, 0.0)])    # two cells to the right
    assert [(a, b) for a, b, _ in _pairs(forward, near)] == [(0, 0)]
    assert _pairs(forward, far) == []


def _two_bays():
    """bays#4 of the real-map bench (seed 21): parked across one narrow bay, to be parked across another; each
    search alone has to turn round in both bays (220 k expansions, 3.4 s before meet.py, with every step the
    same length; long steps in the open find it from the start in fewer)."""
    grid = load_map("maps/real/bays.yaml")
    return grid, (13.525, 4.675, -0.17305013294831584), (15.025, 12.375, 2.828541932511997)


def test_a_manoeuvre_at_both_ends_is_joined_in_the_middle(monkeypatch):
    grid, start, goal = _two_bays()
    cap = Termination(time_limit_s=120.0, max_iterations=40_000)
    options = PlannerOptions(open_step_factor=1, n_yaw_bins=SCENARIO_BINS)
    result = HybridAStar(grid, ROBOT, options).plan(start, goal, cap)
    assert result.extra["found_from"] == "both"
    assert np.allclose(result.states[0, :3], start, atol=1e-9)
    assert check_path(grid, ROBOT, result.states, start, goal) == []  # rollable, collision-free, at the goal
    # without the join the same cap is not enough
    monkeypatch.setattr(search, "MEET_AFTER", 10**9)
    with pytest.raises(NoValidPathFound):
        HybridAStar(grid, ROBOT, options).plan(start, goal, cap)


def test_a_manoeuvre_into_the_goal_is_joined_early():
    """pockets#2 of the real-map bench (seed 0): 13 m along a 1.8 m corridor, then into the goal across another, and
    a turn at the start. The forward tree gets near the goal in a few hundred expansions and then fills the corridor
    there trying to turn into it, while the goal side's tree, grown from the goal, covers the corridor too: a shot
    joins them once both have made search.MEET_AFTER (2 000) expansions. With the join after 10 000 (until issue
    21's tenth round) the goal side found the path alone, after 8 852 expansions (21.87 m)."""
    grid = load_map("maps/real/pockets.yaml")
    start, goal = (6.125, 10.075, 2.9092350581717223), (19.325, 14.725, 2.599295721958983)
    joined = HybridAStar(grid, ROBOT).plan(start, goal)
    assert joined.extra["found_from"] == "both" and joined.expansions < 4_000
    assert check_path(grid, ROBOT, joined.states, start, goal) == []
    assert joined.length_m < 22.0  # 20.89 m


def test_a_problem_solved_before_the_join_starts_is_unchanged(monkeypatch):
    # bays#9 of the real-map bench (seed 0): the goal side finds it in a few thousand expansions
    grid = load_map("maps/real/bays.yaml")
    start, goal = (9.325, 7.675, -0.44124258698566), (11.775, 5.325, 2.9937010606132253)
    joined = HybridAStar(grid, ROBOT).plan(start, goal)
    monkeypatch.setattr(search, "MEET_AFTER", 10**9)
    alone = HybridAStar(grid, ROBOT).plan(start, goal)
    assert joined.expansions == alone.expansions < 10_000
    assert joined.length_m == alone.length_m and joined.extra["found_from"] == "goal"


def _turn(forward, back, clear, tried=()):
    """find_turn over a 20 m × 20 m map whose stored clearance is ``clear`` (a function of x, y on a 0.1 m grid)."""
    f, b = _index(forward, 0.0, -1), _index(back, math.pi, UPRIGHT)
    xs = (np.arange(200) + 0.5) * 0.1
    grid = np.array([[clear(x, y) for x in xs] for y in xs])
    done = np.zeros(40 * 40, dtype=np.bool_)
    for cell in tried:
        done[cell] = True
    return find_turn(f.keys, f.nodes, b.keys, b.nodes, forward[0], forward[1], UPRIGHT, YAW_BINS, grid, 0.0, 0.0, 0.1,
                     done)


def test_a_turn_is_sought_where_the_trees_hold_opposite_headings_in_one_cell_the_roomiest_first():
    # two cells where the goal side faces (in the forward frame) the other way round from the forward tree, one where
    # it faces the same way (a shot joins those), one where the forward node is not upright
    forward = _nodes([(5.1, 5.1, 0.3, UPRIGHT, 1.0), (12.1, 5.1, 0.3, UPRIGHT, 1.0), (8.1, 8.1, 0.3, UPRIGHT, 1.0),
                      (15.1, 15.1, 0.3, 2, 1.0)])
    back = _nodes([(5.2, 5.2, 0.3, UPRIGHT, 2.0), (12.2, 5.2, 0.3, UPRIGHT, 2.0),  # forward frame: 0.3 + π
                   (8.2, 8.2, 0.3 + math.pi, UPRIGHT, 2.0),                         # forward frame: 0.3
                   (15.2, 15.2, 0.3, UPRIGHT, 2.0)])
    i, j, cell = _turn(forward, back, lambda x, y: 1.0 if x > 10 else 0.5)  # more room on the right
    assert (i, j) == (1, 1) and cell == 10 * 40 + 24
    i, j, cell = _turn(forward, back, lambda x, y: 1.0 if x > 10 else 0.5, tried=[cell])
    assert (i, j) == (0, 0)
    assert _turn(forward, back, lambda x, y: 1.0, tried=[10 * 40 + 24, 10 * 40 + 10]) == (-1, -1, -1)
    # as much room in both: the least bucket index (the cell nearer the map's origin row by row), whatever the order
    # of the hash map's slots
    assert _turn(forward, back, lambda x, y: 1.0)[:2] == (0, 0)


def test_a_trees_buckets_grow_and_keep_the_cheapest_node_of_each_bucket():
    rng = np.random.default_rng(7)
    rows = [(float(x), float(y), float(a), UPRIGHT, float(g))
            for x, y, a, g in zip(rng.uniform(0, 20, 3000), rng.uniform(0, 20, 3000), rng.uniform(-4, 4, 3000),
                                  rng.uniform(0, 50, 3000), strict=True)]
    tree = _nodes(rows)
    buckets = Buckets(4)  # 8 slots: grown (rehashed) many times on the way
    for lo in range(0, 3000, 250):  # in rounds, as a search's new nodes are
        buckets.add(tree[0], tree[1], lo, lo + 250, 0.0, -1, GEO)
    best: dict[int, int] = {}
    for k, (x, y, a, _, g) in enumerate(rows):
        b = (int(y // CELL_M) * 40 + int(x // CELL_M)) * YAW_BINS + int((a % (2 * math.pi)) / (2 * math.pi) * YAW_BINS)
        if b not in best or g < rows[best[b]][4]:
            best[b] = k
    assert buckets.count == len(best) and 2 * buckets.count <= buckets.keys.size
    assert all(buckets.node(b) == k for b, k in best.items())
    assert buckets.node(40 * 40 * YAW_BINS + 5) == -1  # never filled


def _turn_round_in_a_corridor():
    """pockets#1 of the real-map bench's seed-1 draw: the start faces up a 1.3 m corridor that bends into another, the
    goal faces back the way the start came. The forward tree reaches the goal's end facing away from its heading, the
    goal side reaches the start's end the same way, and each turns round there state by state (128 k expansions and
    about a second before the turn search between the trees)."""
    grid = load_map("maps/real/pockets.yaml")
    return grid, (18.675, 13.375, 0.7312609262013985), (23.025, 17.175, 2.609458811313899)


def test_two_trees_that_roll_the_way_in_opposite_directions_are_joined_by_a_turn(monkeypatch):
    grid, start, goal = _turn_round_in_a_corridor()
    cap = Termination(time_limit_s=120.0, max_iterations=40_000)
    result = HybridAStar(grid, ROBOT, SCENARIO).plan(start, goal, cap)
    assert result.extra["found_from"] == "both"
    assert 1 <= result.extra["turn_searches"] <= two_ended.TURN_TRIES
    assert 0 < result.extra["turn_expansions"] <= two_ended.TURN_TRIES * two_ended.TURN_BUDGET
    assert result.expansions < 20_000
    assert np.allclose(result.states[0, :3], start, atol=1e-9)
    assert check_path(grid, ROBOT, result.states, start, goal) == []  # rollable, collision-free, at the goal
    # without the turn search the same cap is not enough
    monkeypatch.setattr(two_ended, "TURN_TRIES", 0)
    with pytest.raises(NoValidPathFound):
        HybridAStar(grid, ROBOT, SCENARIO).plan(start, goal, cap)


def test_a_look_for_a_turn_that_finds_no_place_is_not_repeated_every_round(monkeypatch):
    """A look scans every bucket of the map (1.4 ms on the 100 m field); meeting rounds come every chunk. When a look
    finds no cell with opposite headings, the next waits TURN_LOOK_EVERY expansions of both sides."""
    grid, start, goal = _turn_round_in_a_corridor()
    looks = []
    totals = []
    real_turn = two_ended.GoalSide._turn

    def turn(self, forward, clock):
        totals.append(forward.expansions + self.run.expansions)
        return real_turn(self, forward, clock)

    def nowhere(*args):
        looks.append(totals[-1])
        return -1, -1, -1

    monkeypatch.setattr(two_ended.GoalSide, "_turn", turn)
    monkeypatch.setattr(two_ended, "find_turn", nowhere)
    cap = Termination(time_limit_s=120.0, max_iterations=30_000)
    with pytest.raises(NoValidPathFound):
        HybridAStar(grid, ROBOT, SCENARIO).plan(start, goal, cap)
    # shots join the trees from search.MEET_AFTER on, but the first look for a turn waits for TURN_AFTER (a turn
    # search costs up to TURN_BUDGET expansions: sooner, they cost more than they saved on the real-map problems)
    assert min(totals) < two_ended.TURN_AFTER <= min(looks)
    # the two sides make up to 2 × 30 000 expansions
    assert 1 <= len(looks) <= (2 * 30_000 - two_ended.TURN_AFTER) // two_ended.TURN_LOOK_EVERY + 1
    assert all(b - a >= two_ended.TURN_LOOK_EVERY for a, b in itertools.pairwise(looks))


def test_a_turn_search_stops_with_the_plan(monkeypatch):
    """The turn searches run on the plan's clock: once the plan is cancelled (or out of time), a turn search stops
    before its next chunk and no other starts (they ran on unchecked: up to TURN_TRIES × TURN_BUDGET expansions)."""
    grid, start, goal = _turn_round_in_a_corridor()
    cancelled = []
    real_look = two_ended.find_turn

    def look(*args):
        cancelled.append(True)  # the caller cancels the plan as the first look finds its place
        return real_look(*args)

    steps_after = []
    real_step = search._Search.step

    def step(self, budget):
        if cancelled:
            steps_after.append(budget)
        return real_step(self, budget)

    monkeypatch.setattr(two_ended, "find_turn", look)
    monkeypatch.setattr(two_ended, "TURN_BUDGET", 10**9)  # only the clock can stop a turn search
    monkeypatch.setattr(search._Search, "step", step)
    with pytest.raises(PlannerCancelled):
        HybridAStar(grid, ROBOT, SCENARIO).plan(start, goal, Termination(60.0, cancel=lambda: bool(cancelled)))
    assert len(cancelled) == 1 and steps_after == []
