"""The simulated sphere against the geometry of eq. 1 and the profile's actuator limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.closed_loop.simulator import Disturbances, SphereSimulator, SphereState
from planner.errors import InvalidInput
from planner.robot import load_robot

ROBOT = load_robot("zju-60")


def test_constant_roll_rolls_a_circle_of_radius_r_over_tan_roll() -> None:
    sim = SphereSimulator(ROBOT)
    roll = math.radians(12.0)
    state = SphereState(0.0, 0.0, 0.0, roll, 0.4)
    radius = ROBOT.radius_m / math.tan(roll)
    centre = np.array([0.0, radius])  # left turn: centre on the left of the heading
    for _ in range(300):
        state = sim.step(state, 0.4, roll, 0.02).state
        assert math.hypot(state.x - centre[0], state.y - centre[1]) == pytest.approx(radius, abs=1e-6)
    assert state.yaw == pytest.approx(0.4 * 300 * 0.02 / radius, abs=1e-6)


def test_roll_change_at_rest_shifts_the_centre_sideways_by_r_delta_roll() -> None:
    sim = SphereSimulator(ROBOT)
    state = SphereState(1.0, 2.0, math.radians(30.0), 0.0, 0.0)
    for _ in range(100):
        state = sim.step(state, 0.0, ROBOT.max_roll_rad, 0.02).state
    shift = ROBOT.radius_m * state.roll
    assert state.x == pytest.approx(1.0 - shift * math.sin(math.radians(30.0)), abs=1e-9)
    assert state.y == pytest.approx(2.0 + shift * math.cos(math.radians(30.0)), abs=1e-9)
    assert state.yaw == pytest.approx(math.radians(30.0))


def test_roll_is_rate_limited_first_order_and_bounded() -> None:
    sim = SphereSimulator(ROBOT)
    state = SphereState(0.0, 0.0, 0.0)
    rolls = []
    for _ in range(150):
        state = sim.step(state, 0.0, 1.0, 0.02).state  # command beyond the limit
        rolls.append(state.roll)
    rates = np.diff([0.0, *rolls]) / 0.02
    assert rates.max() <= ROBOT.max_roll_rate_rad_s + 1e-9
    assert max(rolls) <= ROBOT.max_roll_rad + 1e-12
    assert rolls[-1] == pytest.approx(ROBOT.max_roll_rad, abs=1e-4)
    # small steps follow the first-order lag: after one time constant 63 % of the way
    state = SphereState(0.0, 0.0, 0.0)
    small = 0.01
    n = round(ROBOT.roll_time_constant_s / 0.02)
    for _ in range(n):
        state = sim.step(state, 0.0, small, 0.02).state
    assert state.roll == pytest.approx(
        small * (1 - math.exp(-n * 0.02 / ROBOT.roll_time_constant_s)), rel=1e-6
    )


def test_speed_is_acceleration_limited_and_wheel_distance_counts_it() -> None:
    sim = SphereSimulator(ROBOT)
    state = SphereState(0.0, 0.0, 0.0)
    step = sim.step(state, 10.0, 0.0, 0.5)
    assert step.state.v == pytest.approx(ROBOT.max_accel_m_s2 * 0.5)
    assert step.wheel_distance_m == pytest.approx(0.5 * ROBOT.max_accel_m_s2 * 0.25)
    assert step.state.x == pytest.approx(step.wheel_distance_m)
    slipped = sim.step(state, 10.0, 0.0, 0.5, ground_factor=0.9)
    assert slipped.state.x == pytest.approx(0.9 * slipped.wheel_distance_m)


def test_noise_names() -> None:
    assert Disturbances.named("none") == Disturbances()
    assert Disturbances.named("default").gnss_noise_m > 0
    with pytest.raises(InvalidInput, match="noise"):
        Disturbances.named("loud")
