"""PID baselines for the pendulum sphere's speed and roll loops (paper 001 §6.6–6.7, Figs. 11 and 13).

Paper 001 compares its LMPC speed controller with a "PID controller" and its improved RSLQR direction
controller with the fuzzy PID of its ref. [16]. Neither structure nor gains are printed, and the fuzzy
rule base is not in paper 001, so it cannot be stated honestly here; both loops get a PID baseline.

A single-loop PID (speed error → τ_p, or roll error → τ_r) cannot be tuned to settle on this plant: the
torque reaches the speed and the roll through the lightly damped pendulum (≈ 8–9 rad/s) and a
non-minimum-phase zero (a torque first rolls the shell *backwards*, ±9 rad/s for roll), and a scan of
single-loop gains found none that settled within the run (docs/pendulum.md). The baseline is therefore
the usual double-loop PID of pendulum-driven spheres, for both loops:

* outer PID: error of the controlled variable (v_ref − ẋ_c, or φ_d − φ) → pendulum angle set-point
  (α_ref or β_ref), clipped to the envelope its model-based rival lives in: for speed the 15° pitch
  bound of paper 001 §5.1 that the LMPC keeps; for roll, which the RSLQR does not bound, the largest
  pendulum angle the auxiliary motor can hold against gravity, asin(τ_max / m_p g l); derivative on the
  measurement, low-pass filtered (``derivative_filter_s``); conditional-integration anti-windup (the
  integral is frozen while the set-point is clipped and the error would push it further); optionally
  (``integral_band``) the integral only runs while |error| is within the band — the integrator gating
  the RSLQR uses, offered so the baseline is not denied a structural advantage (the tuner tries both);
* inner PID: pendulum angle error → motor torque, τ = k_p e + k_i ∫e − k_d ȧ (e = a_ref − a, ȧ the
  measured rate), clipped to the motor's torque limit, with the same conditional-integration
  anti-windup (the integral is needed: holding the pendulum at an angle takes torque against gravity).

Both PIDs measure what the model-based controllers measure (speed, roll, the pendulum angle and rate),
obey the same torque limits and run at the same 50 Hz. Gains come from the profile's ``[dynamics.pid]``
table; they were found by :func:`lab.pendulum.tuning.tune_pid` (``sphereplan controllers
tune``), which minimises the PID's own summed rise time over every case of its figure
(docs/pendulum.md, "The PID baselines and how they were tuned fairly").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from planner.errors import InvalidInput, RobotProfileError
from planner.pendulum.dynamics import PendulumParams
from planner.robot import RobotProfile


@dataclass(frozen=True)
class PIDGains:
    """Outer PID (kp, ki, kd: per unit error → rad of set-point) and inner PID (N m per rad, per rad s, s)."""

    kp: float
    ki: float
    kd: float = 0.0
    inner_kp: float = 40.0
    inner_ki: float = 40.0
    inner_kd: float = 4.0
    derivative_filter_s: float = 0.04
    integral_band: float | None = None

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd", "inner_kp", "inner_ki", "inner_kd"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise InvalidInput(name, f"must be a finite number >= 0, got {value!r}")
        if not (math.isfinite(self.derivative_filter_s) and self.derivative_filter_s > 0):
            raise InvalidInput("derivative_filter_s", f"must be > 0, got {self.derivative_filter_s!r}")
        if self.integral_band is not None and not self.integral_band > 0:
            raise InvalidInput("integral_band", f"must be > 0 or None, got {self.integral_band!r}")

    @property
    def outer_gains(self) -> tuple[float, float, float]:
        return (self.kp, self.ki, self.kd)

    @property
    def inner_gains(self) -> tuple[float, float, float]:
        return (self.inner_kp, self.inner_ki, self.inner_kd)


class PIDController:
    """The double-loop PID at ``ts_s``: :meth:`step` (reference, measurement, pendulum angle and rate) → torque."""

    def __init__(self, gains: PIDGains, torque_limit: float, angle_limit: float, ts_s: float = 0.02) -> None:
        self.g = gains
        self.torque_limit = torque_limit
        self.angle_limit = angle_limit
        self.ts_s = ts_s
        self._alpha = ts_s / (ts_s + gains.derivative_filter_s)
        self.reset()

    def reset(self) -> None:
        self.integral = 0.0
        self.inner_integral = 0.0
        self.derivative = 0.0
        self.setpoint = 0.0
        self._last: float | None = None

    def outer(self, reference: float, measurement: float) -> float:
        """The pendulum-angle set-point (rad) from the controlled variable's error."""
        g = self.g
        error = reference - measurement
        if self._last is not None:
            raw = -(measurement - self._last) / self.ts_s
            self.derivative += self._alpha * (raw - self.derivative)
        self._last = measurement
        unclamped = g.kp * error + self.integral + g.kd * self.derivative
        gated = g.integral_band is not None and abs(error) > g.integral_band
        if not (abs(unclamped) >= self.angle_limit and error * unclamped > 0) and not gated:
            self.integral += g.ki * error * self.ts_s
        out = g.kp * error + self.integral + g.kd * self.derivative
        return max(-self.angle_limit, min(self.angle_limit, out))

    def inner(self, setpoint: float, angle: float, angle_rate: float) -> float:
        """The motor torque (N m) that drives the pendulum angle to ``setpoint``."""
        g = self.g
        error = setpoint - angle
        unclamped = g.inner_kp * error + self.inner_integral - g.inner_kd * angle_rate
        if not (abs(unclamped) >= self.torque_limit and error * unclamped > 0):
            self.inner_integral += g.inner_ki * error * self.ts_s
        tau = g.inner_kp * error + self.inner_integral - g.inner_kd * angle_rate
        return max(-self.torque_limit, min(self.torque_limit, tau))

    def step(self, reference: float, measurement: float, angle: float, angle_rate: float) -> float:
        self.setpoint = self.outer(reference, measurement)
        return self.inner(self.setpoint, angle, angle_rate)


def _gains(section: Mapping[str, object], loop: str) -> PIDGains:
    table = section.get(loop)
    if not isinstance(table, Mapping):
        raise RobotProfileError(f"dynamics.pid.{loop}", "must be a table {kp, ki, kd, inner_kp, inner_ki, inner_kd}")
    values: dict[str, float] = {}
    for key in ("kp", "ki", "kd", "inner_kp", "inner_ki", "inner_kd"):
        value = table.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
            raise RobotProfileError(f"dynamics.pid.{loop}.{key}", f"must be a finite number >= 0, got {value!r}")
        values[key] = float(value)
    band = table.get("integral_band")
    if band is not None and (
        isinstance(band, bool) or not isinstance(band, int | float) or not (math.isfinite(band) and band > 0)
    ):
        raise RobotProfileError(f"dynamics.pid.{loop}.integral_band", f"must be a number > 0, got {band!r}")
    return PIDGains(
        values["kp"], values["ki"], values["kd"], values["inner_kp"], values["inner_ki"], values["inner_kd"],
        integral_band=None if band is None else float(band),
    )


def setpoint_limit(params: PendulumParams, loop: str) -> float:
    """The pendulum set-point clip of the ``speed`` or ``roll`` PID (see the module docstring)."""
    if loop == "speed":
        return params.max_pendulum_angle_rad
    return math.asin(min(1.0, params.max_torque_roll_n_m / params.gravity_torque_n_m))


def pid_gains_from_profile(robot: RobotProfile, loop: str) -> PIDGains:
    """The ``speed`` or ``roll`` PID gains of ``robot``'s ``[dynamics.pid]`` table."""
    dyn = robot.extra.get("dynamics")
    pid = dyn.get("pid") if isinstance(dyn, Mapping) else None
    if not isinstance(pid, Mapping):
        raise RobotProfileError("dynamics.pid", f"robot {robot.name!r} has no [dynamics.pid] table")
    return _gains(pid, loop)


__all__ = ["PIDController", "PIDGains", "pid_gains_from_profile", "setpoint_limit"]
