"""Planning with the real footprint: narrow gaps the polygon fits, reversing with Reeds–Shepp shots, the
preferred clearance, failing fast at dead-end goals and honest failure figures (issue: plan on real maps)."""

import math

import numpy as np
import pytest

from planner.errors import NoValidPathFound, StartOccupied
from planner.hybrid_astar.reeds_shepp import _roll, car_word, sphere_shot
from planner.hybrid_astar.search import GOAL_CHECK_AFTER, HybridAStar, PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path, footprint_distance, footprint_hits

ROBOT = load_robot("zju-60")


def _room(width_m: float, height_m: float, res: float = 0.05) -> np.ndarray:
    occ = np.zeros((round(height_m / res), round(width_m / res)), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    return occ


def test_a_corridor_the_footprint_fits_with_two_centimetres_to_spare_is_found():
    poly = ROBOT.footprint_polygon
    gap = 2 * float(np.abs(poly[:, 1]).max()) + 0.04  # the padded polygon's width + 2 cm each side
    res = 0.02
    occ = _room(8.0, 4.0, res)
    lo, hi = round((2.0 - gap / 2) / res), round((2.0 + gap / 2) / res)
    occ[:lo, 200:300] = True  # a 2 m long corridor between x = 4 and 6 m
    occ[hi:, 200:300] = True
    grid = OccupancyGrid.from_occupied(occ, res, name="corridor")
    start, goal = (1.5, 2.0, 0.0), (7.0, 2.0, 0.0)
    planner = HybridAStar(grid, ROBOT)
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    # the covering circle alone would have refused the corridor: the polygon decided
    assert planner.clearance.circle_margins(planner.footprint, result.states[:, :3]).min() < 0
    assert 0.0 < result.min_clearance_m <= 0.03
    assert result.min_clearance_m == pytest.approx(footprint_distance(grid, ROBOT, result.states), abs=0.02)


def test_free_start_next_to_a_wall_is_not_refused():
    occ = _room(6.0, 4.0)
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    # 3 cm between the padded polygon's side and the wall: the circles touch the wall, the polygon does not
    y = 0.1 + float(np.abs(ROBOT.footprint_polygon[:, 1]).max()) + 0.03
    start = (3.0, y, 0.0)
    assert not footprint_hits(grid, ROBOT, *start)
    planner = HybridAStar(grid, ROBOT)
    assert planner.footprint_margin(start) >= 0
    result = planner.plan(start, (3.0, 2.0, math.pi))
    assert check_path(grid, ROBOT, result.states, start, (3.0, 2.0, math.pi)) == []
    with pytest.raises(StartOccupied):
        planner.plan((3.0, y - 0.05, 0.0), (3.0, 2.0, math.pi))


def test_spheres_reverse_by_default_and_forward_only_is_an_option():
    grid = OccupancyGrid.from_occupied(_room(6.0, 4.0), 0.05)
    assert ROBOT.reversible and HybridAStar(grid, ROBOT).reverse
    assert not HybridAStar(grid, ROBOT, PlannerOptions(allow_reverse=False)).reverse
    assert PlannerOptions.from_dict({"allow_reverse": None}).allow_reverse is None
    # straight back 2 m: a reversing sphere rolls backwards, the forward-only one has to loop round
    start, goal = (4.0, 2.0, 0.0), (2.0, 2.0, 0.0)
    back = HybridAStar(grid, ROBOT).plan(start, goal)
    assert check_path(grid, ROBOT, back.states, start, goal) == []
    assert back.length_m < 2.2 and np.all(back.states[:, 4] <= 0)  # every state rolling backwards (v ≤ 0)


@pytest.mark.parametrize("seed", range(6))
def test_reeds_shepp_shots_land_the_rolled_sphere_on_the_goal(seed: int) -> None:
    rng = np.random.default_rng(seed)
    rho, r, roll = ROBOT.min_turning_radius_m, ROBOT.radius_m, ROBOT.max_roll_rad
    start = (0.0, 0.0, float(rng.uniform(-3, 3)), 0.0)
    goal = (float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)))
    word = car_word(start[:3], goal, rho)
    motions = sphere_shot(start, goal, rho, roll, r)
    if motions is None:  # the roll shifts do not fit a two-segment word: nothing to land
        assert len(word) <= 2
        return
    x, y, yaw = _roll(start, motions, r, 0.0)
    assert math.hypot(x - goal[0], y - goal[1]) < 1e-3 and abs(math.remainder(yaw - goal[2], 2 * math.pi)) < 1e-3
    # the same turning sequence as the car's path, each arc held at the maximum roll
    assert [round(m[1] * rho) for m in motions] == [t for t, _, s in word if s > 1e-9][:len(motions)]
    assert all(abs(m[0]) in (0.0, roll) for m in motions)


def test_a_dead_end_goal_is_reported_long_before_the_time_limit():
    # a 0.8 m wide, 3 m deep slot; the goal inside it faces out, so a forward-only sphere would have to turn
    # round inside it (it could only back in, which it may not)
    occ = _room(20.0, 12.0)
    occ[:, 200:202] = True
    occ[150:168, 200:202] = False        # a door in the dividing wall, at y = 7.5 .. 8.4 m
    occ[120:200, 140:200] = True         # a block west of the door, with a slot cut into it
    occ[151:167, 150:200] = False        # the slot: 0.8 m wide, 2.5 m deep, open only towards the door
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    start, goal = (15.0, 3.0, 0.0), (8.5, 7.95, 0.0)  # facing out of the slot: it would have to turn inside
    planner = HybridAStar(grid, ROBOT, PlannerOptions(allow_reverse=False))
    assert planner.footprint_margin(goal) >= 0
    with pytest.raises(NoValidPathFound) as info:
        planner.plan(start, goal, Termination(120))
    assert "dead end" in str(info.value)
    assert info.value.expansions <= GOAL_CHECK_AFTER + 2 * PlannerOptions().chunk_expansions
    assert info.value.planning_time_s > 0


def test_paths_keep_the_preferred_clearance_where_there_is_room():
    occ = _room(12.0, 6.0)
    occ[50:70, 110:130] = True  # a 1 m pillar in the middle of a 6 m wide hall
    grid = OccupancyGrid.from_occupied(occ, 0.05)
    start, goal = (1.5, 3.0, 0.0), (10.5, 3.0, 0.0)
    result = HybridAStar(grid, ROBOT).plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    assert footprint_distance(grid, ROBOT, result.states) >= ROBOT.preferred_clearance_m - 0.05
