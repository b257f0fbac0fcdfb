"""The goal side of the two-ended search (planner/hybrid_astar/two_ended.py): the conversion of a reverse-problem
path checked by rolling it with the planner's kinematics, a problem only the goal side solves within a small
expansion cap, and the footprint symmetry the reverse problem relies on."""

import math
from dataclasses import replace

import numpy as np
import pytest

from planner.errors import NoValidPathFound
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, _Search
from planner.hybrid_astar.two_ended import GoalSide, centrally_symmetric, goal_side_motions, goal_side_possible
from planner.kinematics import child_pose, wrap
from planner.maps.nav2 import load_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination
from tests.pathcheck import check_path, footprint_hits

ROBOT = load_robot("zju-60")


def _roll_out(pose, motions, radius):
    """End pose of the motions rolled from ``pose`` (upright) with the planner's own child_pose (eq. 1)."""
    x, y, yaw = pose
    roll = 0.0
    for held, curv, s in motions:
        x, y, yaw = child_pose(x, y, yaw, roll, held, curv, radius, s)
        roll = held
    return x, y, yaw, roll


def test_a_reverse_problem_path_converted_rolls_from_its_end_to_its_start_forwards_where_it_rolled_forwards():
    rng = np.random.default_rng(3)
    r = ROBOT.radius_m
    rolls = np.linspace(-ROBOT.max_roll_rad, ROBOT.max_roll_rad, 7)
    for _ in range(50):
        held = rng.choice(rolls, 12)
        motions = [(float(h), float(ROBOT.roll_model.curvature(h)), float(s))
                   for h, s in zip(held, rng.uniform(-1.5, 1.5, 12), strict=True)]
        motions.append((0.0, 0.0, 0.0))
        goal = (float(rng.uniform(-5, 5)), float(rng.uniform(-5, 5)), float(rng.uniform(-math.pi, math.pi)))
        # the reverse problem starts at the goal with the heading turned by π
        ex, ey, eyaw, eroll = _roll_out((goal[0], goal[1], goal[2] + math.pi), motions, r)
        assert eroll == 0.0
        start = (ex, ey, eyaw - math.pi)
        converted = goal_side_motions(motions)
        gx, gy, gyaw, groll = _roll_out(start, converted, r)
        assert math.hypot(gx - goal[0], gy - goal[1]) < 1e-9
        assert abs(wrap(gyaw - goal[2])) < 1e-9 and groll == 0.0
        # the same metres forwards and backwards as the reverse-problem path (not mirrored)
        forward = sum(s for _, _, s in motions if s > 0)
        backward = sum(-s for _, _, s in motions if s < 0)
        assert sum(s for _, _, s in converted if s > 0) == pytest.approx(forward)
        assert sum(-s for _, _, s in converted if s < 0) == pytest.approx(backward)


def _trap_problem():
    """bays#9 of the real-map bench (seed 0): the forward search stays open after 300 k expansions, the search
    from the goal finds the path in a few hundred."""
    grid = load_map("maps/real/bays.yaml")
    start = (9.325, 7.675, -0.44124258698566)
    goal = (11.775, 5.325, 2.9937010606132253)
    return grid, start, goal


def test_a_problem_only_the_goal_side_solves_within_a_small_cap():
    grid, start, goal = _trap_problem()
    cap = Termination(time_limit_s=60.0, max_iterations=20_000)
    with pytest.raises(NoValidPathFound):  # the forward search alone (no goal side) runs out of expansions
        HybridAStar(grid, ROBOT, PlannerOptions(dead_end_check=False)).plan(start, goal, cap)
    planner = HybridAStar(grid, ROBOT)
    result = planner.plan(start, goal, cap)
    assert result.extra["found_from"] == "goal"
    assert result.extra["goal_side_expansions"] > 0
    assert result.expansions < 2 * cap.max_iterations
    # begins exactly at the start, ends within the goal tolerance, rollable and collision-free (independent check)
    assert np.allclose(result.states[0, :3], start, atol=1e-9)
    assert check_path(grid, ROBOT, result.states, start, goal) == []


def test_the_goal_side_path_rolled_from_the_true_start_ends_at_the_goal_and_is_free():
    grid, start, goal = _trap_problem()
    planner = HybridAStar(grid, ROBOT)
    side = GoalSide(planner, start, goal, planner.options, _Search)
    for _ in range(20):
        if side.step(2000):
            break
    assert side.motions is not None and not side.exhausted
    x, y, yaw, roll = _roll_out(start, side.motions, ROBOT.radius_m)
    assert math.hypot(x - goal[0], y - goal[1]) <= planner.options.goal_tolerance_m
    assert abs(wrap(yaw - goal[2])) <= planner.options.goal_tolerance_yaw_rad and roll == 0.0
    fine = planner._densify(start, side.motions, grid.resolution_m / 4)
    assert planner.clearance.footprint_margins(planner.footprint, planner.polygon, fine[:, :3]).min() >= 0
    assert not any(footprint_hits(grid, ROBOT, *p) for p in fine[::4, :3])


def test_a_goal_side_path_that_ends_within_tolerance_of_the_start_is_closed_onto_the_exact_start():
    # smoothers_world#7 of the real-map bench (seed 21): the search from the goal ends on a tolerance hit near the
    # start (it was bays#6, which ends on a shot since children are swept lazily, when popped)
    grid = load_map("maps/real/smoothers_world.yaml")
    start, goal = (13.525, 2.5250000000000004, 0.43932220865584304), (5.175000000000001, 1.225, 0.7909129950198603)
    planner = HybridAStar(grid, ROBOT)
    side = GoalSide(planner, start, goal, planner.options, _Search)
    while side.expansions < 60_000 and not side.step(2000):
        pass
    assert side.motions is not None and side.closed_gaps >= 1
    # rolled from the true start, it ends at the goal up to the shot's landing error, far inside the tolerance
    x, y, yaw, roll = _roll_out(start, side.motions, ROBOT.radius_m)
    assert math.hypot(x - goal[0], y - goal[1]) < 0.01 and abs(wrap(yaw - goal[2])) < 1e-3 and roll == 0.0
    states = planner._densify(start, side.motions, 0.04)
    assert not any(footprint_hits(grid, ROBOT, *p) for p in states[:, :3])


def test_footprint_symmetry_decides_whether_the_goal_side_runs():
    assert centrally_symmetric(np.array([1.0, -1.0, 0.0, 0.0]), np.array([0.0, 0.0, 2.0, -2.0]))
    assert not centrally_symmetric(np.array([1.0, -0.5, -0.5]), np.array([0.0, 0.5, -0.5]))
    grid = OccupancyGrid.from_occupied(np.zeros((60, 60), bool), 0.1, name="open")
    for name in ("zju-60", "zju-80", "daedalus", "spherobot", "texplor"):
        assert goal_side_possible(HybridAStar(grid, load_robot(name)))
    # a footprint that is not the same turned by π (a wedge): the reverse problem would be another problem
    wedge = replace(ROBOT, footprint=((0.35, 0.0), (-0.3, 0.35), (-0.3, -0.35)))
    grid, start, goal = _trap_problem()
    planner = HybridAStar(grid, wedge)
    assert not goal_side_possible(planner)
    # the forward search alone, as before the goal side (which solves this problem for the symmetric footprint)
    with pytest.raises(NoValidPathFound, match="iteration cap"):
        planner.plan(start, goal, Termination(time_limit_s=60.0, max_iterations=6000))


def test_the_goal_side_joins_early_where_the_start_side_stalls_at_the_goal():
    # warehouse#9 of the real-map bench (seed 0): the start side reaches the goal's surroundings at once, facing the
    # wrong way between a rack's end and a box, and floods them; the goal side finds the path in under 100
    # expansions. With the goal side joining after 2 000 expansions (chunks of 2 000) the plan took 3 880 in all.
    grid = load_map("maps/real/warehouse.yaml")
    start = (-5.605, -2.275, -1.4003907527669615)
    goal = (-3.775, 10.655, 0.48322497323790925)
    planner = HybridAStar(grid, ROBOT)
    result = planner.plan(start, goal, Termination(time_limit_s=60.0))
    assert result.extra["found_from"] == "goal"
    assert result.expansions < 1500
    assert check_path(grid, ROBOT, result.states, start, goal) == []


def test_a_goal_parked_across_a_narrow_bay_is_found_from_the_goal_side():
    # bays#5 of the real-map bench's seed-1 draw: start at the end of one bay, goal across another. The goal side
    # found the path after 85 k expansions but its search had kept a motion that clips a cell between two sweep
    # samples, so the final exact check dropped it and every later join through it (372 k expansions, 3.8 s);
    # sampled as densely as that check where only the polygon fits, it is found after 9 k goal-side expansions.
    grid = load_map("maps/real/bays.yaml")
    start = (3.2750000000000004, 2.9250000000000003, -1.8645883699713708)
    goal = (7.825, 11.075000000000001, 0.48191853022539144)
    result = HybridAStar(grid, ROBOT).plan(start, goal, Termination(time_limit_s=60.0))
    assert result.expansions < 60_000
    assert check_path(grid, ROBOT, result.states, start, goal) == []
