"""Wheel odometry (eq. 2) against the simulated eq. 1, and the eq. 3 fusion filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.closed_loop.localization import FusionFilter, OdometryIncrement, WheelOdometry
from planner.closed_loop.simulator import SphereSimulator, SphereState
from planner.robot import load_robot

ROBOT = load_robot("zju-60")


def _drive(
    commands: list[tuple[float, float]], steps_each: int = 100
) -> tuple[list[SphereState], list[float]]:
    sim = SphereSimulator(ROBOT)
    state = SphereState(0.0, 0.0, 0.3)
    states, wheels = [state], []
    for v, roll in commands:
        for _ in range(steps_each):
            step = sim.step(state, v, roll, 0.02)
            state = step.state
            states.append(state)
            wheels.append(step.wheel_distance_m)
    return states, wheels


def test_noise_free_odometry_reproduces_eq1() -> None:
    states, wheels = _drive([(0.5, 0.2), (0.5, -0.25), (0.3, 0.0), (-0.3, 0.15)])
    odo = WheelOdometry(ROBOT, (0.0, 0.0, 0.3))
    for a, b, ds in zip(states[:-1], states[1:], wheels, strict=True):
        odo.update(OdometryIncrement(ds, a.roll, b.roll))
    end = states[-1]
    assert math.hypot(odo.pose[0] - end.x, odo.pose[1] - end.y) < 0.01
    assert odo.pose[2] == pytest.approx(end.yaw, abs=2e-3)


def test_without_gnss_the_filter_is_odometry() -> None:
    states, wheels = _drive([(0.5, 0.2), (0.5, -0.1)], 50)
    odo = WheelOdometry(ROBOT, (0.0, 0.0, 0.3))
    kf = FusionFilter(ROBOT, (0.0, 0.0, 0.3))
    for a, b, ds in zip(states[:-1], states[1:], wheels, strict=True):
        inc = OdometryIncrement(ds * 1.05, a.roll + 0.01, b.roll + 0.01)  # biased sensors
        odo.update(inc)
        kf.predict(inc)
    np.testing.assert_allclose(kf.pose, odo.pose)
    assert np.trace(kf.cov) > np.trace(FusionFilter(ROBOT, (0.0, 0.0, 0.3)).cov)  # uncertainty grew


def test_gnss_corrects_position_and_through_the_jacobian_the_yaw() -> None:
    rng = np.random.default_rng(3)
    states, wheels = _drive([(0.5, 0.0), (0.5, 0.1), (0.5, -0.1), (0.5, 0.0)], 150)
    odo = WheelOdometry(ROBOT, (0.0, 0.0, 0.3 + 0.1))  # both start with a 0.1 rad yaw error
    kf = FusionFilter(ROBOT, (0.0, 0.0, 0.3 + 0.1))
    for k, (a, b, ds) in enumerate(zip(states[:-1], states[1:], wheels, strict=True)):
        inc = OdometryIncrement(ds * 0.97, a.roll + 0.002, b.roll + 0.002)
        odo.update(inc)
        kf.predict(inc)
        if k % 5 == 0:
            kf.correct((b.x + rng.normal(0, 0.02), b.y + rng.normal(0, 0.02)))
    end = states[-1]
    odo_err = math.hypot(odo.pose[0] - end.x, odo.pose[1] - end.y)
    kf_err = math.hypot(kf.pose[0] - end.x, kf.pose[1] - end.y)
    assert kf_err < 0.05 < odo_err
    assert abs(kf.pose[2] - end.yaw) < 0.03 < abs(odo.pose[2] - end.yaw)
