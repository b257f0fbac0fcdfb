"""A search's setup, reused between the searches of a planner: finished searches give their closed-set bitsets
back cleared (closed_set.BitsetPool), the goal-independent parameters are computed once; a search that reuses them
decides as one that does not."""

import math

import numpy as np

from planner.hybrid_astar import closed_set, kernels
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, _Search
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot

ROBOT = load_robot("zju-60")


def _rooms() -> OccupancyGrid:
    occupied = np.zeros((160, 240), bool)
    occupied[:, :2] = occupied[:, -2:] = occupied[:2, :] = occupied[-2:, :] = True
    occupied[:110, 115:120] = True
    occupied[60:, 170:175] = True
    return OccupancyGrid.from_occupied(occupied, 0.05, name="rooms")


def test_a_finished_search_gives_back_a_bitset_that_is_all_zero() -> None:
    planner = HybridAStar(_rooms(), ROBOT, PlannerOptions())
    start, goal = (1.0, 1.0, 0.0), (10.5, 6.0, math.pi / 2)
    run = _Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), planner.options, planner.reverse)
    assert run.closed.size > 0 and len(planner.bitset_pool) == 0
    run.run_for(2000, _no_limit())
    bits = run.closed
    assert run.expansions > 10 and bits.any()
    del run
    assert len(planner.bitset_pool) == 1
    taken = planner.bitset_pool.take()
    assert taken is bits and not taken.any()  # cleared node by node: every key the search closed


def test_a_large_search_clears_its_bitset_whole() -> None:
    planner = HybridAStar(_rooms(), ROBOT, PlannerOptions())
    start, goal = (1.0, 1.0, 0.0), (10.5, 6.0, math.pi / 2)
    run = _Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), planner.options, planner.reverse)
    run.run_for(3000, _no_limit())
    n_nodes = int(run.counters[kernels.C_NODES])
    bits = run.closed
    assert n_nodes > 0 and bits.any()
    import planner.hybrid_astar.search as S

    keep, S.CLEAR_BYTES_PER_NODE = S.CLEAR_BYTES_PER_NODE, bits.size  # every search counts as large
    try:
        del run
    finally:
        S.CLEAR_BYTES_PER_NODE = keep
    assert not planner.bitset_pool.take().any()


def test_plans_with_reused_bitsets_are_the_plans_with_new_ones() -> None:
    grid = _rooms()
    problems = [((1.0, 1.0, 0.0), (10.5, 6.0, math.pi / 2)), ((10.5, 6.0, 0.0), (1.0, 7.0, math.pi)),
                ((3.0, 6.5, -math.pi / 2), (9.0, 1.5, 0.0))]
    pooled = HybridAStar(grid, ROBOT, PlannerOptions())
    for start, goal in problems * 2:
        fresh = HybridAStar(grid, ROBOT, PlannerOptions())
        a, b = pooled.plan(start, goal), fresh.plan(start, goal)
        assert a.expansions == b.expansions and np.array_equal(a.states, b.states)
    assert 1 <= len(pooled.bitset_pool) <= pooled.bitset_pool.keep


def test_the_pool_keeps_at_most_its_share_and_a_wrong_size_is_not_used() -> None:
    pool = closed_set.BitsetPool(keep=2)
    for _ in range(3):
        pool.give_back(np.zeros(8, np.uint8))
    assert len(pool) == 2
    bits, _ = closed_set.new_sets(8 * 100, 16, pool)  # needs 101 bytes: the pooled 8-byte ones do not fit
    assert bits.size == closed_set.dense_bytes(800) and not bits.any()


def _no_limit():
    from planner.termination import Termination

    return Termination(60.0).start()


def test_the_parameters_towards_a_goal_are_a_fresh_planners_and_a_change_to_them_stays_in_that_search() -> None:
    grid = _rooms()
    planner = HybridAStar(grid, ROBOT, PlannerOptions())
    first = planner._params((1.0, 1.0, 0.0), True)
    first[kernels.P_STEP] = 99.0  # a search's own copy
    goal = (10.5, 6.0, math.pi / 2)
    again = planner._params(goal, True)
    fresh = HybridAStar(grid, ROBOT, PlannerOptions())._params(goal, True)
    assert np.array_equal(again, fresh) and again[kernels.P_STEP] == planner.resolved_step_m
    assert tuple(again[[kernels.P_GX, kernels.P_GY, kernels.P_GYAW]]) == goal
    assert again[kernels.P_GCOS] == math.cos(goal[2]) and again[kernels.P_GSIN] == math.sin(goal[2])
    forward = planner._params(goal, False)  # the other direction has its own
    assert forward[kernels.P_ALLOW_REVERSE] == 0.0 and again[kernels.P_ALLOW_REVERSE] == 1.0


def test_the_search_is_given_its_footprints_convexity_once() -> None:
    """kernels.P_CONVEX holds clearance.convex_turn of the planner's polygon, so the search's footprint tests do not
    work it out per call (70 ns, a fifth of a call near a wall); a search with it unset (0: the even-odd test) or
    given it decides the same."""
    from planner.maps.clearance import convex_turn

    grid = _rooms()
    planner = HybridAStar(grid, ROBOT, PlannerOptions())
    p = planner._params((10.5, 6.0, math.pi / 2), True)
    assert p[kernels.P_CONVEX] == convex_turn(planner._px, planner._py) != 0
    start, goal = (1.5, 1.5, 0.0), (10.5, 6.0, math.pi / 2)
    run = _Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), planner.options, True)
    plain = _Search(planner, start, goal, planner.holonomic(goal[:2], start[:2]), planner.options, True)
    plain.p[kernels.P_CONVEX] = 0.0
    for search in (run, plain):
        search.run_for(3000, _no_limit())
    n = int(run.counters[kernels.C_NODES])
    assert n > 100 and n == int(plain.counters[kernels.C_NODES])
    assert np.array_equal(run.node_f[:n], plain.node_f[:n])


def test_the_childrens_turns_are_worked_out_once_per_step_and_long_step() -> None:
    """A planner keeps kernels.child_turns per (step, long-step count): a search with other values gets its own,
    the same values get the same array, and every one is what child_turns gives."""
    planner = HybridAStar(_rooms(), ROBOT, PlannerOptions())
    p = planner._params((10.5, 6.0, math.pi / 2), True)
    longer, shorter = p.copy(), p.copy()
    longer[kernels.P_LONG] = p[kernels.P_LONG] + 2.0
    shorter[kernels.P_STEP] = 0.5 * p[kernels.P_STEP]
    got = [planner.child_turns(q) for q in (p, longer, shorter)]
    for q, turns in zip((p, longer, shorter), got, strict=True):
        assert np.array_equal(turns, kernels.child_turns(planner.curvatures, q))
    assert not np.array_equal(got[0], got[1]) and not np.array_equal(got[0], got[2])
    assert planner.child_turns(p.copy()) is got[0]
