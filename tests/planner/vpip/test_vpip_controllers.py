"""Roll PID / pitch PI (paper 000 Fig. 5, Table 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import RobotProfileError
from planner.vpip.controllers import (
    PID,
    PITCH_GAINS,
    ROLL_GAINS,
    PIDGains,
    PitchController,
    RollController,
    gains_from_section,
)


def test_anti_windup_keeps_integral_bounded_in_saturation() -> None:
    for ctl in (RollController(), PitchController()):
        g = ctl.gains
        for _ in range(5000):
            out = ctl.step(1.0)  # large error: output saturated
            assert abs(out) <= g.output_limit + 1e-15
            assert abs(ctl.integral) <= g.integral_limit + 1e-15
        # conditional integration: the integrator did not grow while saturated
        assert ctl.integral == pytest.approx(0.0)
        # so the output leaves saturation as soon as the error reverses
        assert ctl.step(-1.0) < 0


def test_integral_part_is_clipped_when_not_saturated() -> None:
    ctl = PID(PIDGains(kp=0.0, ki=1.0, output_limit=10.0, integral_limit=0.05), 0.01)
    for _ in range(1000):
        ctl.step(0.5)
    assert ctl.integral == pytest.approx(0.05)


def test_derivative_filter_attenuates_noise_and_passes_ramps() -> None:
    rng = np.random.default_rng(3)
    noise = rng.normal(0.0, 0.01, 4000)
    ctl = PID(PIDGains(kp=0.0, ki=0.0, kd=1.0), 0.01)
    filtered = []
    for e in noise:
        ctl.step(float(e))
        filtered.append(ctl.derivative)
    raw = np.diff(noise) / 0.01
    assert np.std(filtered[100:]) < 0.8 * np.std(raw[100:])
    ramp = PID(PIDGains(kp=0.0, ki=0.0, kd=1.0), 0.01)
    for k in range(200):
        ramp.step(0.3 * k * 0.01)
    assert ramp.derivative == pytest.approx(0.3, rel=1e-6)


def test_signs_and_reset() -> None:
    roll = RollController()
    assert roll.command(math.radians(5), 0.0) > 0  # leaning too far left -> lower the left side
    pitch = PitchController()
    assert pitch.command(0.0, 1.0) > 0  # too slow -> pitch forward
    pitch.reset()
    assert pitch.integral == 0.0 and pitch.derivative == 0.0


def test_gains_from_profile_section() -> None:
    roll, pitch, rate = gains_from_section({})
    assert roll == ROLL_GAINS and pitch.kp == PITCH_GAINS.kp and rate == 100.0
    roll, _, _ = gains_from_section({"roll_kp": 1.5})
    assert roll.kp == 1.5
    with pytest.raises(RobotProfileError, match=r"vpip\.roll_kd"):
        gains_from_section({"roll_kd": "x"})
