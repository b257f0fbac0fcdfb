"""The two VPIP angle controllers of paper 000 Fig. 5: roll PID and pitch PI, run at 100 Hz.

* Roll: PID on the roll error → φ_VPIP. Conditional-integration anti-windup, derivative through a
  first-order low-pass (cut-off 50 Hz), output limited to ±20°, integral part limited to ±5°.
* Pitch: PI on the rotational-speed error → θ_VPIP. Conditional-integration anti-windup, output
  limited to ±40°, integral part limited to ±10°.

Gains are Table 1's (roll 3.0/2.0/3.5, pitch 10.1/2.1). The paper does not give their units; here
they are SI: roll error in rad → φ_VPIP in rad, speed error in rad/s → θ_VPIP in rad, and the anti-windup
limits bound the integral *part* ``k_i·∫e dt`` (Table 1 footnote: "Anti-Windup limits the Integral Part").
A profile's ``[vpip]`` table may override any of them (``roll_kp``, ``roll_ki``, ``roll_kd``,
``roll_derivative_cutoff_hz``, ``roll_limit_deg``, ``roll_integral_limit_deg``, ``pitch_kp``,
``pitch_ki``, ``pitch_limit_deg``, ``pitch_integral_limit_deg``, ``control_rate_hz``).

Conditional integration: the integral is frozen while the unclamped output is saturated and the error
would drive it further into saturation; otherwise it integrates and is clipped to its limit.
The derivative is that of the error, filtered by the backward-Euler low-pass
``d ← d + α(d_raw − d)``, ``α = dt / (dt + 1/(2π f_c))`` (at 100 Hz and f_c = 50 Hz, α ≈ 0.76; a
bilinear design is impossible because 50 Hz is the Nyquist frequency). The first step has no
derivative (no kick from the initial error).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from planner.errors import InvalidInput, RobotProfileError


@dataclass(frozen=True)
class PIDGains:
    """Gains and limits of one controller (SI). ``derivative_cutoff_hz`` is unused when ``kd`` is 0."""

    kp: float
    ki: float
    kd: float = 0.0
    output_limit: float = math.inf
    integral_limit: float = math.inf
    derivative_cutoff_hz: float = 50.0

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise InvalidInput(name, f"must be a finite number >= 0, got {value!r}")
        for name in ("output_limit", "integral_limit", "derivative_cutoff_hz"):
            if not getattr(self, name) > 0:
                raise InvalidInput(name, f"must be > 0, got {getattr(self, name)!r}")


ROLL_GAINS = PIDGains(
    kp=3.0,
    ki=2.0,
    kd=3.5,
    output_limit=math.radians(20.0),
    integral_limit=math.radians(5.0),
    derivative_cutoff_hz=50.0,
)
"""Table 1 roll PID: 3.0/2.0/3.5, 50 Hz derivative filter, |φ_VPIP| ≤ 20°, integral part ≤ 5°."""

PITCH_GAINS = PIDGains(kp=10.1, ki=2.1, output_limit=math.radians(40.0), integral_limit=math.radians(10.0))
"""Table 1 pitch PI: 10.1/2.1, |θ_VPIP| ≤ 40°, integral part ≤ 10°."""

CONTROL_RATE_HZ = 100.0
"""Table 1: overall control frequency."""


class PID:
    """Discrete PID with conditional-integration anti-windup and a low-pass filtered derivative.

    ``step(error)`` advances by ``dt_s`` and returns the clipped output. State: :attr:`integral` (the
    integral part k_i·∫e, output units), :attr:`derivative` (filtered de/dt), the previous error.
    """

    def __init__(self, gains: PIDGains, dt_s: float) -> None:
        if not (math.isfinite(dt_s) and dt_s > 0):
            raise InvalidInput("dt_s", f"must be a finite number > 0, got {dt_s!r}")
        self.gains = gains
        self.dt_s = dt_s
        tau = 1.0 / (2.0 * math.pi * gains.derivative_cutoff_hz)
        self.alpha = dt_s / (dt_s + tau)
        self.reset()

    def reset(self) -> None:
        self.integral = 0.0
        self.derivative = 0.0
        self._last_error: float | None = None
        self.saturated = False

    def step(self, error: float) -> float:
        g = self.gains
        if g.kd > 0 and self._last_error is not None:
            raw = (error - self._last_error) / self.dt_s
            self.derivative += self.alpha * (raw - self.derivative)
        self._last_error = error
        p = g.kp * error
        d = g.kd * self.derivative
        unclamped = p + self.integral + d
        self.saturated = abs(unclamped) >= g.output_limit
        if not (self.saturated and error * unclamped > 0):
            self.integral += g.ki * error * self.dt_s
            self.integral = max(-g.integral_limit, min(g.integral_limit, self.integral))
        out = p + self.integral + d
        return max(-g.output_limit, min(g.output_limit, out))


class RollController(PID):
    """Roll PID: error = roll − desired roll (rad) → φ_VPIP (rad), same sign as the roll (paper §4)."""

    def __init__(self, gains: PIDGains = ROLL_GAINS, dt_s: float = 1.0 / CONTROL_RATE_HZ) -> None:
        super().__init__(gains, dt_s)

    def command(self, roll_rad: float, desired_roll_rad: float) -> float:
        return self.step(roll_rad - desired_roll_rad)


class PitchController(PID):
    """Pitch PI: error = desired ω − ω (rad/s) → θ_VPIP (rad), > 0 drives forward."""

    def __init__(self, gains: PIDGains = PITCH_GAINS, dt_s: float = 1.0 / CONTROL_RATE_HZ) -> None:
        if gains.kd != 0:
            gains = replace(gains, kd=0.0)
        super().__init__(gains, dt_s)

    def command(self, omega_rad_s: float, desired_omega_rad_s: float) -> float:
        return self.step(desired_omega_rad_s - omega_rad_s)


def _num(section: Mapping[str, Any], key: str, default: float) -> float:
    if key not in section:
        return default
    value = section[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(float(value)):
        raise RobotProfileError(f"vpip.{key}", f"must be a finite number, got {value!r}")
    return float(value)


def gains_from_section(section: Mapping[str, Any]) -> tuple[PIDGains, PIDGains, float]:
    """Roll gains, pitch gains and control rate (Hz) from a profile's ``[vpip]`` table (Table 1 defaults)."""
    roll = PIDGains(
        kp=_num(section, "roll_kp", ROLL_GAINS.kp),
        ki=_num(section, "roll_ki", ROLL_GAINS.ki),
        kd=_num(section, "roll_kd", ROLL_GAINS.kd),
        output_limit=math.radians(_num(section, "roll_limit_deg", 20.0)),
        integral_limit=math.radians(_num(section, "roll_integral_limit_deg", 5.0)),
        derivative_cutoff_hz=_num(section, "roll_derivative_cutoff_hz", 50.0),
    )
    pitch = PIDGains(
        kp=_num(section, "pitch_kp", PITCH_GAINS.kp),
        ki=_num(section, "pitch_ki", PITCH_GAINS.ki),
        output_limit=math.radians(_num(section, "pitch_limit_deg", 40.0)),
        integral_limit=math.radians(_num(section, "pitch_integral_limit_deg", 10.0)),
    )
    rate = _num(section, "control_rate_hz", CONTROL_RATE_HZ)
    if rate <= 0:
        raise RobotProfileError("vpip.control_rate_hz", f"must be > 0, got {rate}")
    return roll, pitch, rate
