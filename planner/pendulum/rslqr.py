"""Improved robust-servo LQR for the pendulum sphere's roll (direction): paper 001 §5.3, eq. 26–32.

* Model: the roll sub-model linearised at rest, x_r = (β, β̇, φ, φ̇), u_r = τ_r, output y_r = φ (derived
  in :mod:`planner.pendulum.dynamics`; it is controllable, tested).
* Robust servo (eq. 28, Wise's RSLQR): the state is augmented with the integral of the output error,
  ż = φ − φ_d, and the infinite-horizon LQR (eq. 26) of the augmented system ξ = (z, x − x_d),
  A_ξ = [[0, C], [0, A]], B_ξ = [0; B], gives K = R⁻¹B_ξᵀP from ``scipy.linalg.solve_continuous_are``;
  u_s = −K_x (x − x_d) − K_i z with x_d = (0, 0, φ_d, 0) (eq. 27's reference form). The integral is frozen
  while the torque saturates in the direction of the error (conditional integration, as for the PID).
* State compensation δ (eq. 29–30): the linearisation drops the pendulum's centripetal term
  n = m_p r l β̇² sin β from the shell row. With M_rL⁻¹ = [[M_r1, M_r2], [M_r2, M_r4]] a torque u moves φ̈
  by (M_r2 + M_r4)·u and n moves it by M_r4·n, so the torque that cancels n's effect on φ̈ is
  δ = −M_r4 n / (M_r2 + M_r4). The printed eq. 29 has n / (M_r2 + M_r4); its numerator cannot be checked
  against the PDF, so the derived form is used and tested (adding δ removes the term's effect on φ̈ of
  the linearised model).
* Velocity feed-forward ρ (eq. 31): ρ = sgn(φ_d)(a_r1 v² + a_r2 |v|). The paper fits a_r1, a_r2 by
  experiment; on our plant the steady turn needs τ_r = (m + I_s/r²) v² tan φ (the yaw coupling of the
  dynamics module), so a_r1 = (m + I_s/r²) tan|φ_d| and a_r2 = 0 (tested: ρ is the torque that holds a
  steady turn of the plant).
* Steady pendulum roll (added): in a steady turn the pendulum hangs at β_ss ≠ 0 (from the same balance,
  m_p g l sin β_ss + Ω m_p v l cos β_ss = ρ). Eq. 27 regulates β to 0, so its k_r1 β term fights the
  feed-forward and the integral must unwind k_r1 β_ss: the roll then creeps to the target over seconds
  (1.0 m/s, 0.19 rad: still 3 % short after 5 s). x_d = (β_ss, 0, φ_d, 0) removes that;
  ``steady_state_reference=False`` gives the printed eq. 27.
* Output (eq. 32): u = u_s + δ + ρ, clipped to the auxiliary motor's limit.

The LQR is designed in continuous time (as the paper does) and run at 50 Hz; the discrete closed loop
is stable (tested). Weights are assumptions documented in docs/pendulum.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_continuous_are

from planner.errors import InvalidInput
from planner.pendulum.dynamics import PendulumParams, linear_model


@dataclass(frozen=True)
class RSLQRSettings:
    """Weights of eq. 26 on (∫e, β, β̇, φ − φ_d, φ̇) and on τ_r (per N m²); which compensations to use.

    The default q is :func:`lab.pendulum.tuning.tune_rslqr`'s result for the scheduled design
    (the same search, objective and limits as the roll PID's tuning); r was then doubled from 0.02 to
    0.04 because the tuned loop swung the pendulum past the motor's holding angle in a closed-loop
    U-turn (docs/pendulum.md); ``integral_band_rad`` None = no integrator gating.
    ``scheduled`` designs the gains about rolling straight at the measured speed (rounded to
    :data:`SCHEDULE_STEP_M_S`) instead of at rest: the same eq. 26–28 on the linearisation that includes
    the roll's stiffness (m + I_s/r²) v² at speed."""

    ts_s: float = 0.02
    q: tuple[float, float, float, float, float] = (15.15, 0.4389, 0.03086, 14130.0, 11.36)
    r: float = 0.04
    state_compensation: bool = True
    velocity_feedforward: bool = True
    steady_state_reference: bool = True
    integral_band_rad: float | None = 0.02
    scheduled: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.ts_s) and self.ts_s > 0):
            raise InvalidInput("ts_s", f"must be a finite number > 0, got {self.ts_s!r}")
        if any(w < 0 for w in self.q) or not self.r > 0:
            raise InvalidInput("q", "weights must be >= 0 and r > 0")


def rslqr_gains(
    params: PendulumParams, settings: RSLQRSettings, speed: float = 0.0
) -> tuple[np.ndarray, float, np.ndarray]:
    """(K_x (4,), K_i, P (5, 5)) from the continuous algebraic Riccati equation of the augmented model
    linearised at rest (``speed`` 0, the paper's design) or about rolling straight at ``speed``."""
    lin = linear_model(params, "roll", speed=speed)
    a_aug = np.zeros((5, 5))
    a_aug[0, 3] = 1.0  # ż = φ − φ_d
    a_aug[1:, 1:] = lin.a
    b_aug = np.concatenate([[0.0], lin.b]).reshape(5, 1)
    p = solve_continuous_are(a_aug, b_aug, np.diag(settings.q), np.array([[settings.r]]))
    k = (b_aug.T @ p).ravel() / settings.r
    return k[1:], float(k[0]), p


SCHEDULE_STEP_M_S = 0.05
"""Speed grid of the scheduled design (m/s)."""


def sampled_spectral_radius(params: PendulumParams, settings: RSLQRSettings, speed: float = 0.0) -> float:
    """Spectral radius of the linear closed loop as it runs: ZOH plant at ``ts_s``, forward-Euler integral,
    the continuous-time gains. Below 1 = the sampled design is stable (the LQR is designed in continuous
    time, so very high gains can be stable on paper and unstable at 50 Hz). With ``speed`` ≠ 0: the
    linear loop about rolling straight at that speed, with the gains the controller uses there."""
    k_x, k_i, _ = rslqr_gains(params, settings, speed if settings.scheduled else 0.0)
    lin = linear_model(params, "roll", speed=speed)
    ad, bd, _ = lin.discretise(settings.ts_s)
    cl = np.zeros((5, 5))
    cl[0, 0], cl[0, 3] = 1.0, settings.ts_s
    cl[1:, 1:] = ad - np.outer(bd, k_x)
    cl[1:, 0] = -bd * k_i
    return float(max(abs(np.linalg.eigvals(cl))))


class RSLQRRollController:
    """Eq. 26–32 once per ``ts_s``: :meth:`step` (measured x_r, φ_d, speed v) → τ_r (N m)."""

    def __init__(self, params: PendulumParams, settings: RSLQRSettings | None = None) -> None:
        self.params = params
        self.s = settings or RSLQRSettings()
        self.k_x, self.k_i, _ = rslqr_gains(params, self.s)
        self._schedule: dict[int, tuple[np.ndarray, float]] = {0: (self.k_x, self.k_i)}
        m_inv = linear_model(params, "roll").m_inv
        self.m_r2, self.m_r4 = float(m_inv[0, 1]), float(m_inv[1, 1])
        self.tau_max = params.max_torque_roll_n_m
        self.reset()

    def reset(self) -> None:
        self.integral = 0.0
        self.last_parts = (0.0, 0.0, 0.0)

    def state_compensation(self, beta: float, beta_dot: float) -> float:
        """δ of eq. 29 (derived form, see the module docstring)."""
        p = self.params
        n = p.pendulum_mass_kg * p.radius_m * p.pendulum_length_m * beta_dot * beta_dot * math.sin(beta)
        return -self.m_r4 * n / (self.m_r2 + self.m_r4)

    def velocity_feedforward(self, v: float, phi_d: float) -> float:
        """ρ of eq. 31: the torque a steady turn at roll φ_d and speed v needs."""
        p = self.params
        a_r1 = (p.total_mass_kg + p.shell_inertia_kg_m2 / p.radius_m**2) * math.tan(abs(phi_d))
        a_r2 = 0.0
        return math.copysign(1.0, phi_d) * (a_r1 * v * v + a_r2 * abs(v)) if phi_d != 0.0 else 0.0

    def steady_beta(self, v: float, phi_d: float, tau: float) -> float:
        """The pendulum roll β_ss that holds torque ``tau`` in a steady turn at (v, φ_d)."""
        p = self.params
        grav = p.gravity_torque_n_m
        yaw = v * math.tan(phi_d) / p.radius_m * p.pendulum_mass_kg * v * p.pendulum_length_m
        ratio = max(-1.0, min(1.0, tau / math.hypot(grav, yaw)))
        return math.asin(ratio) - math.atan2(yaw, grav)

    def gains_at(self, v: float) -> tuple[np.ndarray, float]:
        """(K_x, K_i) used at wheel speed ``v``: the design at rest, or (``scheduled``) about rolling at v."""
        if not self.s.scheduled:
            return self.k_x, self.k_i
        key = int(round(abs(v) / SCHEDULE_STEP_M_S))
        if key not in self._schedule:
            k_x, k_i, _ = rslqr_gains(self.params, self.s, key * SCHEDULE_STEP_M_S)
            self._schedule[key] = (k_x, k_i)
        return self._schedule[key]

    def step(self, x: np.ndarray, phi_d: float, v: float = 0.0) -> float:
        """Measured x_r = (β, β̇, φ, φ̇), desired roll φ_d (rad), wheel speed v (m/s) → τ_r."""
        beta, beta_dot, phi, phi_dot = (float(c) for c in x)
        k_x, k_i = self.gains_at(v)
        rho = self.velocity_feedforward(v, phi_d) if self.s.velocity_feedforward else 0.0
        beta_d = self.steady_beta(v, phi_d, rho) if self.s.steady_state_reference else 0.0
        dev = np.array([beta - beta_d, beta_dot, phi - phi_d, phi_dot])
        u_s = -float(k_x @ dev) - k_i * self.integral
        delta = self.state_compensation(beta, beta_dot) if self.s.state_compensation else 0.0
        u = u_s + delta + rho
        err = phi - phi_d
        # conditional integration: hold the integral while saturated and integrating would push further
        pushes = -k_i * err * u > 0
        band = self.s.integral_band_rad
        if not (abs(u) >= self.tau_max and pushes) and (band is None or abs(err) <= band):
            self.integral += err * self.s.ts_s
        self.last_parts = (u_s, delta, rho)
        return max(-self.tau_max, min(self.tau_max, u))


__all__ = ["SCHEDULE_STEP_M_S", "RSLQRRollController", "RSLQRSettings", "rslqr_gains", "sampled_spectral_radius"]
