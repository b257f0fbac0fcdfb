"""The compiled smoother's pieces (planner/hybrid_astar/smoothing.py) against the Python they replaced, and the
curvature it gives the roll changes it adds. (Its paths are checked by the smoothing tests through
``HybridAStar._smooth`` / ``_shortcut``.)"""

import math

import numpy as np
import pytest

from planner.hybrid_astar import kernels, smoothing
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.kinematics import subdivide
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot

ROBOT = load_robot("zju-60")


def _random_motions(rng: np.random.Generator, n: int) -> list[tuple[float, float, float]]:
    rolls = rng.choice([-ROBOT.max_roll_rad, -0.1, 0.0, 0.1, ROBOT.max_roll_rad], n)
    lengths = rng.choice([-1.0, 0.0, 1.0], n) * rng.uniform(0.0, 1.3, n)
    return [(float(r), float(ROBOT.roll_model.curvature(float(r))), float(s))
            for r, s in zip(rolls, lengths, strict=True)]


def test_subdividing_splits_each_motion_into_equal_pieces_no_longer_than_the_step() -> None:
    rng = np.random.default_rng(3)
    for n in (0, 1, 2, 7, 40):
        for _ in range(20):
            motions = _random_motions(rng, n)
            for step in (0.2, 0.35, 1.0):
                pieces = subdivide(motions, step)
                k = 0
                for held, curv, s in motions:  # each motion: the fewest equal pieces within the step, in order
                    parts = max(1, math.ceil(abs(s) / step - 1e-9))
                    assert pieces[k:k + parts] == [(held, curv, s / parts)] * parts
                    assert abs(s / parts) <= step + 1e-9
                    k += parts
                assert k == len(pieces)


def _rows(lengths) -> np.ndarray:
    return np.array([(0.0, 0.0, s) for s in lengths], float).reshape(-1, 3)


def test_cusps_count_the_changes_of_direction() -> None:
    rows = _rows
    assert smoothing.cusps(rows([])) == 0
    assert smoothing.cusps(rows([1.0, 0.5, 0.0, 2.0])) == 0
    assert smoothing.cusps(rows([1.0, -0.5])) == 1
    assert smoothing.cusps(rows([1.0, 0.0, -0.5, 0.0, 0.0, 0.3, 0.2, -1.0])) == 3  # a roll change keeps the direction
    assert smoothing.cusps(rows([0.0, -1.0, 0.0, -2.0, 1.0])) == 1
    rng = np.random.default_rng(5)
    for _ in range(200):  # against a count of sign changes among the motions that move
        lengths = rng.choice([-1.0, 0.0, 1.0], int(rng.integers(0, 30)))
        moving = np.sign(lengths[lengths != 0])
        assert smoothing.cusps(rows(lengths)) == int((np.diff(moving) != 0).sum())


def test_a_roll_change_added_by_a_shortcut_curves_as_the_robot_does_at_that_roll() -> None:
    """Every shortcut ends with a motion of length 0 bringing the roll to its knot's; its curvature is the roll
    model's (looked up, forwards and in the mirrored reverse shots), so the path stays a valid chain of motions."""
    grid = OccupancyGrid.from_occupied(np.zeros((300, 300), dtype=bool), 0.05, name="open")
    planner = HybridAStar(grid, ROBOT)
    roll = ROBOT.max_roll_rad
    kappa = float(ROBOT.roll_model.curvature(roll))
    start = (10.0, 7.5, 0.0)
    p = planner._params((0.0, 0.0, 0.0), True)
    paths = {
        "backwards with a manoeuvre": [(0.0, 0.0, -1.0), (roll, kappa, -0.6), (-roll, -kappa, 0.6), (0.0, 0.0, -1.0),
                                       (0.0, 0.0, 0.0)],
        "forwards zig-zag": [(roll, kappa, 0.5), (-roll, -kappa, 0.5)] * 4 + [(0.0, 0.0, 0.0)],
        "forwards then backwards": [(roll, kappa, 0.4), (-roll, -kappa, 0.4)] * 3
        + [(-roll, -kappa, -0.4), (roll, kappa, -0.4)] * 3 + [(0.0, 0.0, 0.0)],
    }
    for name, motions in paths.items():
        out = planner._shortcut(start, motions, p, 24)
        assert smoothing.path_length(*start, np.array(out, float), ROBOT.radius_m) < smoothing.path_length(
            *start, np.array(motions, float), ROBOT.radius_m) - 0.1, name  # it shortcut something
        for held, curv, _ in [m for m in out if m[2] == 0.0]:  # the roll changes a shortcut ends with
            assert curv == ROBOT.roll_model.curvature(held) + 0.0, name
        for held, curv, _ in out:
            assert curv == pytest.approx(ROBOT.roll_model.curvature(held), rel=1e-3, abs=1e-9), name
        assert not any(math.copysign(1.0, v) < 0 and v == 0.0 for m in out for v in m), name  # no −0.0


def test_a_roll_missing_from_the_curvature_table_is_an_error_not_a_guess() -> None:
    keys, curvs = smoothing.curvature_table(np.array([[0.1, 0.5, 1.0]]), [0.3], ROBOT.roll_model.curvature)
    assert sorted(keys.tolist()) == [-0.3, -0.1, 0.0, 0.1, 0.3]
    with pytest.raises(ValueError, match="curvature table"):
        smoothing._curvature_at(0.2, keys, curvs)


def _end(start, motions) -> np.ndarray:
    from planner.kinematics import motion_knots
    return motion_knots(start[0], start[1], start[2], 0.0, np.array(motions, float).reshape(-1, 3), ROBOT.radius_m)[-1]


def test_a_small_turn_is_shortcut_with_a_gentler_roll_when_that_is_shorter() -> None:
    """A shortcut is rolled with a gentler held turn when that is the shorter path (each roll change shifts the
    sphere sideways by radius × the change). A bend made of two short arcs at the sharpest turn with a straight
    between: the sharpest turn's shortcut (one arc) still pays two shifts of r·φmax (0.16 m); the gentlest held
    turn's pays a third of that and is shorter. Both end on the same pose, and the result is a valid chain of
    motions."""
    grid = OccupancyGrid.from_occupied(np.zeros((400, 400), dtype=bool), 0.05, name="open")
    planner = HybridAStar(grid, ROBOT)
    k = len(planner.rolls) // 2 + 1  # the gentlest turn held by the search
    assert 0.0 < planner.rolls[k] < ROBOT.max_roll_rad / 2
    start = (3.0, 3.0, 0.0)
    # a bend the search might leave, cut into step-long pieces
    turn, kappa = ROBOT.max_roll_rad, float(ROBOT.roll_model.curvature(ROBOT.max_roll_rad))
    motions = subdivide([(0.0, 0.0, 2.0), (turn, kappa, 0.3), (0.0, 0.0, 0.5), (turn, kappa, 0.2), (0.0, 0.0, 2.0),
                         (0.0, 0.0, 0.0)], 0.2)
    p = planner._params((0.0, 0.0, 0.0), False)
    sharp_only = p.copy()
    sharp_only[kernels.P_GENTLE_N] = 0
    length = {}
    for name, params in (("gentle", p), ("sharp", sharp_only)):
        out = planner._shortcut(start, motions, params, 24)
        np.testing.assert_allclose(_end(start, out)[:3], _end(start, motions)[:3], atol=2e-4)
        for held, curv, _ in out:
            assert curv == pytest.approx(ROBOT.roll_model.curvature(held), rel=1e-3, abs=1e-9), name
        length[name] = smoothing.path_length(*start, np.array(out, float), ROBOT.radius_m)
        turning = {round(abs(held), 9) for held, _, s in out if s != 0.0 and held != 0.0}
        if name == "gentle":
            assert turning and max(turning) < ROBOT.max_roll_rad - 1e-9  # no sharpest turn left
        else:
            assert turning == {round(ROBOT.max_roll_rad, 9)}
    assert length["gentle"] < length["sharp"] - 0.1
    assert length["sharp"] < smoothing.path_length(*start, np.array(motions, float), ROBOT.radius_m) - 0.05


def test_the_gentler_turns_offered_to_the_smoother_span_the_held_ones() -> None:
    """Every held turn gentler than the sharpest (7 rolls: two), or at most MAX_GENTLE spread from the gentlest to
    the sharpest of them (31 rolls: 14 held, 4 offered), as (radius, roll) pairs the roll model agrees with."""
    grid = OccupancyGrid.from_occupied(np.zeros((100, 100), dtype=bool), 0.05, name="open")
    for n_rolls, want in ((7, [4, 5]), (31, [16, 20, 25, 29])):
        planner = HybridAStar(grid, ROBOT, PlannerOptions(n_rolls=n_rolls))
        p = planner._params((1.0, 1.0, 0.0), True)
        assert int(p[kernels.P_GENTLE_N]) == len(want)
        for g, k in enumerate(want):
            radius, roll = p[kernels.P_GENTLE + 2 * g], p[kernels.P_GENTLE + 2 * g + 1]
            assert roll == planner.rolls[k] and radius == pytest.approx(1.0 / planner.curvatures[k])
            assert 1.0 / radius == pytest.approx(ROBOT.roll_model.curvature(roll))
