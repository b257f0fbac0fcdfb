"""The Hybrid-A* step (corrected eq. 14) against numerical integration of eq. 1 of paper 001."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from planner.kinematics import child_pose, densify_motions, motion_knots, wrap

R = 0.30


def integrate_eq1(x, y, yaw, roll_p, roll_c, s, ramp_s=1e-3, speed=0.5):
    """Eq. 1 with roll ramping linearly from roll_p to roll_c over ``ramp_s`` seconds while v = 0, then
    rolling at speed ±0.5 m/s with constant roll until |s| is covered."""
    rate = (roll_c - roll_p) / ramp_s

    def ramp(t, q):
        return [-R * rate * math.sin(q[2]), R * rate * math.cos(q[2]), 0.0]

    q = solve_ivp(ramp, (0, ramp_s), [x, y, yaw], rtol=1e-11, atol=1e-12).y[:, -1]
    v = math.copysign(speed, s) if s else 0.0

    def roll_on(t, q):
        return [v * math.cos(q[2]), v * math.sin(q[2]), v * math.tan(roll_c) / R]

    if s == 0:
        return q
    return solve_ivp(roll_on, (0, abs(s) / speed), q, rtol=1e-11, atol=1e-12).y[:, -1]


@pytest.mark.parametrize(
    ("roll_p", "roll_c", "s"),
    [
        (0.0, 0.0, 0.5),                     # straight
        (0.2, 0.2, 0.7),                     # left arc, no roll change
        (-0.25, -0.25, 1.3),                 # right arc
        (0.0, 0.26, 0.4),                    # roll change then arc
        (0.26, -0.26, 0.4),                  # full swing: the largest sideways shift
        (0.1, 0.0, 0.3),                     # back to upright (φc = 0)
        (0.0, 0.2, -0.6),                    # reverse
        (0.15, -0.1, 0.0),                   # pure roll change
    ],
)
def test_step_matches_integration_of_eq1(roll_p, roll_c, s):
    rng = np.random.default_rng(7)
    for _ in range(3):
        x, y, yaw = rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-math.pi, math.pi)
        got = child_pose(x, y, yaw, roll_p, roll_c, math.tan(roll_c) / R, R, s)
        want = integrate_eq1(x, y, yaw, roll_p, roll_c, s)
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 1e-6
        assert abs(math.remainder(got[2] - want[2], 2 * math.pi)) < 1e-6


def test_printed_eq14_is_wrong_and_ours_is_right():
    """The printed eq. 14a uses v·Δt in front of (sin θc − sin θp); for a real arc that misses badly."""
    x, y, yaw, roll, s = 0.0, 0.0, 0.3, 0.2, 1.0
    kappa = math.tan(roll) / R
    yaw_c = yaw + kappa * s
    printed_x = x + s * (math.sin(yaw_c) - math.sin(yaw))
    want = integrate_eq1(x, y, yaw, roll, roll, s)
    assert abs(printed_x - want[0]) > 0.1
    assert abs(child_pose(x, y, yaw, roll, roll, kappa, R, s)[0] - want[0]) < 1e-6


def test_densify_spacing_and_end():
    motions = np.array([[0.2, math.tan(0.2) / R, 1.0], [-0.26, -math.tan(0.26) / R, 0.7], [0.0, 0.0, 0.0]])
    poses = densify_motions(np.array([1.0, 2.0, 0.5]), motions, R, 0.04)
    step = np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1]))
    assert step.max() <= 0.04 + 1e-9
    x, y, yaw, roll = 1.0, 2.0, 0.5, 0.0
    for held, curv, s in motions:
        x, y, yaw = child_pose(x, y, yaw, roll, held, curv, R, s)
        roll = held
    assert np.allclose(poses[-1, :3], [x, y, yaw])
    assert poses[-1, 3] == 0.0


def test_motion_knots_follow_the_motions_and_count_arcs_and_shifts() -> None:
    """motion_knots (compiled, the smoother's knots): each row is child_pose of the previous row, the last one
    is where densify_motions ends, and the distance adds |s| and r·|Δroll| per motion."""
    rng = np.random.default_rng(3)
    radius = 0.3
    motions = np.column_stack([rng.uniform(-0.26, 0.26, 40), rng.uniform(-1.5, 1.5, 40), rng.uniform(-0.8, 0.8, 40)])
    motions[::5, 1] = 0.0  # straights
    motions[-1] = (0.0, 0.0, 0.0)  # back upright on the spot
    knots = motion_knots(1.0, -2.0, 0.4, 0.0, motions, radius)
    assert knots.shape == (41, 5)
    x, y, yaw, roll, dist = 1.0, -2.0, 0.4, 0.0, 0.0
    for k, (held, curv, s) in enumerate(motions):
        x, y, yaw = child_pose(x, y, yaw, roll, held, curv, radius, s)
        dist += abs(s) + radius * abs(held - roll)
        roll = held
        assert np.allclose(knots[k + 1], (x, y, yaw, roll, dist), rtol=0, atol=1e-12)
    end = densify_motions(np.array([1.0, -2.0, 0.4]), motions, radius, 0.01)[-1]
    assert np.allclose(knots[-1, :3], end[:3], atol=1e-9)
    shifts = radius * np.abs(np.diff(motions[:, 0], prepend=0.0)).sum()
    assert knots[-1, 4] == pytest.approx(np.abs(motions[:, 2]).sum() + shifts)


@pytest.mark.parametrize("a", [0.0, 1.0, -1.0, math.pi, -math.pi, 3 * math.pi, -3 * math.pi, 2 * math.pi,
                               math.pi + 1e-12, -math.pi - 1e-12, 7.5, -7.5, 123.456, -1e4, 1e6])
def test_wrap_moves_by_whole_turns_into_the_half_open_range(a: float) -> None:
    w = wrap(a)
    assert -math.pi < w <= math.pi
    # the same angle: sine and cosine agree (atan2 of them is the reference wrap), to rounding of the turns removed
    assert math.isclose(math.sin(w), math.sin(a), abs_tol=1e-9) and math.isclose(math.cos(w), math.cos(a), abs_tol=1e-9)
    assert abs(w - math.atan2(math.sin(a), math.cos(a))) < 1e-9 or abs(abs(w) - math.pi) < 1e-9
    if -math.pi < a <= math.pi:
        assert w == a  # an angle in range comes back as it is, to the bit


def test_wrap_of_the_half_turn_boundary_and_of_non_finite_angles() -> None:
    assert wrap(-math.pi) == math.pi and wrap(math.pi) == math.pi
    assert math.isclose(wrap(3 * math.pi), math.pi, abs_tol=1e-15) and wrap(3 * math.pi) <= math.pi
    assert math.isnan(wrap(math.nan)) and math.isnan(wrap(math.inf)) and math.isnan(wrap(-math.inf))
