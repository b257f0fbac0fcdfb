"""Offset-free linear MPC for the pendulum sphere's speed: paper 001 §5.2, eq. 20–25.

* Model (eq. 20): the pitch sub-model linearised at rest, x_p = (α, α̇, x_c, ẋ_c), u_p = τ_p, with the
  rolling resistance as the constant V_c of the travel direction. A_c and B_c are derived from the
  model of :mod:`planner.pendulum.dynamics` (:func:`~planner.pendulum.dynamics.linear_model`), not copied
  from the printed eq. 20 (SEED-NOTES: the extracted matrices are unreliable).
* Discretisation (eq. 21) at T_s = 20 ms (50 Hz): exact zero-order hold instead of the paper's forward
  Euler, which makes the lightly damped pendulum mode unstable at this rate (tested).
* Disturbance (eq. 22): w = two constant generalised torques, one on the pendulum row and one on the
  shell row of the pitch model (B_w = the ZOH of M_L⁻¹, C_w = 0). Any static model error — another
  floor's rolling resistance, sin α ≠ α, the damping — is a pair of such torques at steady state, so
  the Kalman filter's innovations can vanish and the controller is offset-free (a single torque
  entering like τ_p, B_w = B_d, left a 15 % speed offset on the rubber floor: it cannot explain the
  measured pendulum pitch and the speed at once). The augmented model is observable from the measured
  (α, α̇, x_c, ẋ_c) (tested). A Kalman filter (eq. 3's predict/correct form) on (x, w) gives x̂ and ŵ
  every period.
* Target (eq. 24): the steady state (x_ref, u_ref) that holds the reference speed under ŵ solves
  (A_d − I) x + B_d u + B_w ŵ + V_d = 0 with ẋ_c = v_ref (x_c excluded: it integrates and has no
  weight); the prediction's drift is V_p = V_d + B_w ŵ (the printed "V_d − B_w w*" has the sign of a
  disturbance defined the other way round).
* Cost (eq. 23) and condensed QP (eq. 25): Σ_{i=1}^{N_p−1} ‖x_i − x_ref‖²_Q + ‖x_{N_p} − x_ref‖²_P +
  Σ_{i=0}^{N_u−1} r (u_i − u_ref)², inputs held after the control horizon (u_k = u_{N_u−1}, k ≥ N_u),
  |τ_p| ≤ τ_max. H_p = 2(B̄ᵀQ̄B̄ + R̄) is constant; f = 2(B̄ᵀQ̄(Āx* + V̄ − x̄_ref) − R̄ū_ref) each period.
* Pitch bound (added; eq. 23 bounds only the input): |α_i| ≤ α_max (15°, paper 001 §5.1 — "the pendulum
  always swings less than 15°", the premise of the linearisation) on the predicted pitch, softened by
  one slack ε ≥ 0 with an exact penalty (ρ₁ ε + ρ₂ ε²) so the QP stays feasible when a disturbance has
  already pushed the pendulum past it. Without it the pure eq. 23 LMPC swung the pendulum to 78° on
  the 1.5 m/s step.
  The terminal weight P is the discrete Riccati solution of the (α, α̇, ẋ_c) system (an assumption; the
  paper names P_p without giving it). The QP goes to qpOASES through CasADi (:class:`BoxQP`).

The numbers (horizons, weights, filter noises) are assumptions documented in docs/pendulum.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm, solve_discrete_are

from planner.errors import InvalidInput
from planner.pendulum.dynamics import PendulumParams, linear_model
from planner.pendulum.qp import DenseQP

_RED = [0, 1, 3]  # (α, α̇, ẋ_c): the states that feed back; x_c only integrates


@dataclass(frozen=True)
class LMPCSettings:
    """LMPC numbers (assumptions). Weights are on (α, α̇, x_c, ẋ_c) and on τ_p − τ_ref (per N m²)."""

    ts_s: float = 0.02
    horizon: int = 50
    control_horizon: int = 25
    q: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 4000.0)
    r: float = 0.002
    qpsol: str = "qpoases"
    pitch_limit: bool = True
    slack_weights: tuple[float, float] = (1e6, 1e4)
    kf_process_std: tuple[float, float, float, float, float, float] = (1e-3, 1e-2, 1e-4, 5e-3, 0.05, 0.05)
    kf_measurement_std: tuple[float, float, float, float] = (3e-3, 1e-2, 1e-3, 1e-2)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.ts_s) and self.ts_s > 0):
            raise InvalidInput("ts_s", f"must be a finite number > 0, got {self.ts_s!r}")
        if self.horizon < 1 or not 1 <= self.control_horizon <= self.horizon:
            raise InvalidInput("control_horizon", "needs 1 <= control_horizon <= horizon")
        if any(w < 0 for w in self.q) or not self.r > 0:
            raise InvalidInput("q", "weights must be >= 0 and r > 0")


class _Model:
    """The discretised model (A_d, B_d, V_d, B_w) for one travel direction."""

    def __init__(self, params: PendulumParams, s: LMPCSettings, forward: float) -> None:
        lin = linear_model(params, "pitch", forward=forward)
        self.a, self.b, self.v = lin.discretise(s.ts_s)
        self.bw = np.column_stack([_zoh_input(lin.a, col, s.ts_s) for col in disturbance_inputs(params)])


def disturbance_inputs(params: PendulumParams) -> list[np.ndarray]:
    """Continuous B_w columns: a unit generalised torque on the pendulum row, then on the shell row."""
    lin = linear_model(params, "pitch", forward=0.0)
    r = params.radius_m
    return [np.array([0.0, lin.m_inv[0, k], 0.0, r * lin.m_inv[1, k]]) for k in (0, 1)]


def _zoh_input(a: np.ndarray, b: np.ndarray, ts: float) -> np.ndarray:
    n = a.shape[0]
    big = np.zeros((n + 1, n + 1))
    big[:n, :n] = a
    big[:n, n] = b
    return np.asarray(expm(big * ts)[:n, n])


class LMPCSpeedController:
    """Eq. 20–25: Kalman filter → target → condensed QP (qpOASES) → τ_p, once per ``ts_s``."""

    def __init__(self, params: PendulumParams, settings: LMPCSettings | None = None) -> None:
        self.params = params
        self.s = settings or LMPCSettings()
        s = self.s
        self.tau_max = params.max_torque_pitch_n_m
        self.models = {d: _Model(params, s, d) for d in (-1.0, 0.0, 1.0)}
        a, b = self.models[1.0].a, self.models[1.0].b  # A_d, B_d, B_w do not depend on the direction
        self.a_d, self.b_d, self.b_w = a, b, self.models[1.0].bw
        n, npred, nu = 4, s.horizon, s.control_horizon
        q = np.diag(s.q)
        q_red = q[np.ix_(_RED, _RED)]
        p_red = solve_discrete_are(a[np.ix_(_RED, _RED)], b[_RED].reshape(3, 1), q_red, np.array([[s.r]]))
        self.p_terminal = np.zeros((4, 4))
        self.p_terminal[np.ix_(_RED, _RED)] = p_red
        # condensed prediction x_{i+1} = A^{i+1} x0 + Σ_j A^{i−j} B u_j + Σ_{j≤i} A^j d
        powers = [np.eye(n)]
        for _ in range(npred):
            powers.append(a @ powers[-1])
        self.phi = np.vstack(powers[1:])
        gamma = np.zeros((n * npred, npred))
        for i in range(npred):
            for j in range(i + 1):
                gamma[n * i : n * i + n, j] = powers[i - j] @ b
        block = np.zeros((npred, nu))
        for k in range(npred):
            block[k, min(k, nu - 1)] = 1.0
        self.gamma = gamma @ block
        self.psi = np.vstack([sum(powers[: i + 1]) for i in range(npred)])
        q_bar = np.kron(np.eye(npred), q)
        q_bar[-n:, -n:] = self.p_terminal
        self.q_bar = q_bar
        self.r_bar = s.r * np.eye(nu)
        self.hessian = 2.0 * (self.gamma.T @ q_bar @ self.gamma + self.r_bar)
        self._gq = self.gamma.T @ q_bar
        self.alpha_max = params.max_pendulum_angle_rad
        if s.pitch_limit:  # z = (u_0 … u_{N_u−1}, ε)
            g_alpha = self.gamma[0::n]
            h = np.zeros((nu + 1, nu + 1))
            h[:nu, :nu] = self.hessian
            h[nu, nu] = 2.0 * s.slack_weights[1]
            a_con = np.vstack([np.hstack([g_alpha, -np.ones((npred, 1))]), np.hstack([g_alpha, np.ones((npred, 1))])])
            self.qp = DenseQP(h, a_con, s.qpsol)
            self._lb = np.concatenate([np.full(nu, -self.tau_max), [0.0]])
            self._ub = np.concatenate([np.full(nu, self.tau_max), [np.inf]])
        else:
            self.qp = DenseQP(self.hessian, None, s.qpsol)
            self._lb = np.full(nu, -self.tau_max)
            self._ub = np.full(nu, self.tau_max)
        # Kalman filter on (x, w)
        aa = np.eye(6)
        aa[:4, :4] = a
        aa[:4, 4:] = self.b_w
        self._aa = aa
        self._ba = np.concatenate([b, [0.0, 0.0]])
        self._c = np.hstack([np.eye(4), np.zeros((4, 2))])
        self._qkf = np.diag(np.square(s.kf_process_std))
        self._rkf = np.diag(np.square(s.kf_measurement_std))
        self.reset()

    def reset(self, y0: np.ndarray | None = None) -> None:
        """Start the filter at measurement ``y0`` (zeros when None) with no disturbance estimate."""
        self.xhat = np.zeros(6)
        if y0 is not None:
            self.xhat[:4] = y0
        self.cov = np.diag([1e-4, 1e-3, 1e-6, 1e-4, 1.0, 1.0])
        self._started = y0 is not None
        self.last_solve_ms = 0.0
        self.last_qp_ok = True
        self.last_target: tuple[np.ndarray, float] = (np.zeros(4), 0.0)

    @property
    def disturbance(self) -> np.ndarray:
        """Estimated disturbance ŵ (N m): generalised torques on the pendulum and the shell."""
        return self.xhat[4:].copy()

    def _direction(self, v_ref: float, v: float) -> float:
        if v_ref != 0.0:
            return math.copysign(1.0, v_ref)
        return math.copysign(1.0, v) if abs(v) > self.params.rolling_speed_eps_m_s else 0.0

    def target(self, v_ref: float, w: np.ndarray, direction: float) -> tuple[np.ndarray, float]:
        """(x_ref (4,), u_ref): the model's steady state at speed ``v_ref`` under disturbance ``w``."""
        m = self.models[direction]
        ar = self.a_d[np.ix_(_RED, _RED)] - np.eye(3)
        br = self.b_d[_RED]
        lhs = np.zeros((4, 4))
        lhs[:3, :3] = ar
        lhs[:3, 3] = br
        lhs[3, 2] = 1.0
        rhs = np.concatenate([-(m.v[_RED] + self.b_w[_RED] @ w), [v_ref]])
        z = np.linalg.solve(lhs, rhs)
        x_ref = np.array([z[0], z[1], 0.0, z[2]])
        return x_ref, float(z[3])

    def step(self, y: np.ndarray, v_ref: float) -> float:
        """One control period: measurement ``y`` = (α, α̇, x_c, ẋ_c) → motor torque τ_p (N m)."""
        y = np.asarray(y, dtype=float)
        if not self._started:
            self.reset(y)
        # Kalman correction with y_k
        c, p = self._c, self.cov
        gain = p @ c.T @ np.linalg.inv(c @ p @ c.T + self._rkf)
        self.xhat = self.xhat + gain @ (y - c @ self.xhat)
        self.cov = (np.eye(6) - gain @ c) @ p
        x0, w = self.xhat[:4], self.xhat[4:]
        direction = self._direction(v_ref, float(y[3]))
        m = self.models[direction]
        x_ref, u_ref = self.target(v_ref, w, direction)
        self.last_target = (x_ref, u_ref)
        drift = m.v + self.b_w @ w
        predicted = self.phi @ x0 + self.psi @ drift  # the free response (all inputs zero)
        u_refs = np.full(self.s.control_horizon, u_ref)
        f = 2.0 * (self._gq @ (predicted - np.tile(x_ref, self.s.horizon)) - self.r_bar @ u_refs)
        t0 = time.perf_counter()
        if self.s.pitch_limit:
            alpha_free = predicted[0::4]
            inf = np.full(self.s.horizon, np.inf)
            u = self.qp.solve(
                np.concatenate([f, [self.s.slack_weights[0]]]),
                self._lb,
                self._ub,
                np.concatenate([-inf, -self.alpha_max - alpha_free]),
                np.concatenate([self.alpha_max - alpha_free, inf]),
            )
        else:
            u = self.qp.solve(f, self._lb, self._ub)
        self.last_solve_ms = (time.perf_counter() - t0) * 1e3
        self.last_qp_ok = self.qp.last_ok
        tau = float(u[0])
        # Kalman prediction to the next period with the torque actually applied
        self.xhat = self._aa @ self.xhat + self._ba * tau + np.concatenate([m.v, [0.0, 0.0]])
        self.cov = self._aa @ self.cov @ self._aa.T + self._qkf
        return tau


__all__ = ["LMPCSettings", "LMPCSpeedController"]
