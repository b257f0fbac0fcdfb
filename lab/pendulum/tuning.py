"""How the pendulum sphere's baseline PIDs and the RSLQR's weights were tuned (docs/pendulum.md).

* :func:`tune_pid` — all gains of the double-loop PID by a seeded differential evolution + Nelder–Mead,
  minimising the PID's summed rise time over every case of its figure subject to the limits the model-based
  controller meets on the same cases (overshoot ≤ 10 %, settled within ±5 % before the run ends, steady-state
  error ≤ 2 % of the step, no torque chatter once settled);
* :func:`tune_rslqr` tunes the RSLQR's weights the same way.
"""

from __future__ import annotations

import itertools
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.pendulum.dynamics import IA, IB, PendulumParams, PendulumSpherePlant, params_from_profile
from planner.pendulum.pid import PIDController, PIDGains, pid_gains_from_profile, setpoint_limit
from planner.pendulum.rslqr import RSLQRSettings, sampled_spectral_radius
from planner.pendulum.steps import (
    FIG11_CASES,
    FIG13_CASES,
    MAX_OVERSHOOT,
    MAX_STEADY_ERROR,
    MAX_TAIL_VARIATION,
    PITCH_TOLERANCE_RAD,
    ROLL_DURATION_S,
    SPEED_DURATION_S,
    TS_S,
    roll_step,
    speed_step,
    step_metrics,
)
from planner.robot import RobotProfile, load_robot

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class TuneResult:
    """Tuned gains, their objective (summed rise time, s) and each case's metrics."""

    gains: PIDGains
    objective: float
    cases: list[dict[str, Any]]
    evaluations: int


def _pid_cases(robot: RobotProfile, loop: str, gains: PIDGains) -> list[dict[str, Any]]:
    if loop == "speed":
        return [
            {k: v for k, v in speed_step(robot, "pid", sp, fl, gains=gains).items() if k != "series"}
            for sp, fl in FIG11_CASES
        ]
    return [
        {k: v for k, v in roll_step(robot, "pid", sp, ph, gains=gains).items() if k != "series"}
        for sp, ph in FIG13_CASES
    ]


def pitch_tolerance(robot: RobotProfile) -> float:
    """How far (rad) past the 15° pitch bound the speed PID may swing: as far as the LMPC's softened bound
    lets the LMPC itself go over the Fig. 11 cases on this robot, and at least :data:`PITCH_TOLERANCE_RAD`."""
    params = params_from_profile(robot)
    peak = max(speed_step(robot, "lmpc", sp, fl)["max_pitch_rad"] for sp, fl in FIG11_CASES)
    return max(PITCH_TOLERANCE_RAD, peak - params.max_pendulum_angle_rad)


def _objective(
    loop: str, cases: Sequence[dict[str, Any]], params: PendulumParams, tolerance: float = PITCH_TOLERANCE_RAD
) -> float:
    """Summed rise time plus penalties for each limit the model-based controller meets and the PID breaks."""
    duration = SPEED_DURATION_S if loop == "speed" else ROLL_DURATION_S
    total = 0.0
    for c in cases:
        step = c["speed_m_s"] if loop == "speed" else abs(c["roll_rad"])
        rise = c["rise_time_s"]
        total += duration if rise is None else rise
        total += 50.0 * max(0.0, c["overshoot"] - MAX_OVERSHOOT)
        total += duration if c["settling_time_s"] is None else 0.0
        total += 50.0 * max(0.0, c["steady_state_error"] / step - MAX_STEADY_ERROR)
        if loop == "speed":
            total += 1000.0 * max(0.0, c["max_pitch_rad"] - params.max_pendulum_angle_rad - tolerance)
        tau_max = params.max_torque("pitch" if loop == "speed" else "roll")
        total += 5.0 * max(0.0, c["torque_variation_last_s_n_m"] / tau_max - MAX_TAIL_VARIATION)
    return total


def inner_step(params: PendulumParams, loop: str, gains: PIDGains, angle: float = math.radians(8.0),
               duration_s: float = 1.5) -> dict[str, float | None]:
    """The PID's inner loop alone: from rest, a pendulum-angle set-point step of ``angle`` (pitch for
    ``speed``, roll for ``roll``); the step figures of the pendulum angle."""
    plant = PendulumSpherePlant(params)
    sub = "pitch" if loop == "speed" else "roll"
    pid = PIDController(gains, params.max_torque(sub), setpoint_limit(params, loop), TS_S)
    ia, iad = (IA, IA + 1) if loop == "speed" else (IB, IB + 1)
    s = np.zeros(11)
    t, y = [], []
    for k in range(int(round(duration_s / TS_S)) + 1):
        tau = pid.inner(angle, float(s[ia]), float(s[iad]))
        t.append(k * TS_S)
        y.append(float(s[ia]))
        s = plant.step(s, tau, 0.0, TS_S) if loop == "speed" else plant.step(s, 0.0, tau, TS_S)
    return step_metrics(np.array(t), np.array(y), 0.0, angle, tail_s=0.3)


def _inner_objective(m: dict[str, float | None], duration: float) -> float:
    """Rise plus settling time of the pendulum-angle step, overshoot beyond 10 % penalised."""
    rise, settle = m["rise_time_s"], m["settling_time_s"]
    total = duration if rise is None else float(rise)
    total += 2.0 * duration if settle is None else float(settle)
    return total + 50.0 * max(0.0, float(m["overshoot"] or 0.0) - MAX_OVERSHOOT)


def _nelder_mead(fun: Callable[[np.ndarray], float], x0: np.ndarray, max_iter: int) -> tuple[np.ndarray, float]:
    from scipy.optimize import minimize

    res = minimize(fun, x0, method="Nelder-Mead", options={"maxiter": max_iter, "xatol": 0.02, "fatol": 1e-3})
    return np.asarray(res.x), float(res.fun)


def tune_pid(
    robot: RobotProfile | str | None,
    loop: str,
    generations: int = 10,
    population: int = 8,
    polish_iter: int = 80,
    seed: int = 0,
) -> TuneResult:
    """Tune the ``speed`` or ``roll`` double-loop PID: all six gains and the integrator band at once.

    The objective is the PID's own summed rise time over every case of Fig. 11 (speed) or Fig. 13 (roll),
    plus penalties for breaking the limits the model-based controller meets on the same cases: overshoot
    ≤ 10 %, settled within ±5 % before the run ends, steady-state error ≤ 2 % of the step (and for speed
    the 15° pendulum pitch bound of paper 001 §5.1, which the set-point clip already enforces, exceeded by
    no more than the LMPC exceeds it on the same robot: :func:`pitch_tolerance`).

    Search: the inner loop alone is tuned first on 8° pendulum-angle steps from rest (a log grid around
    the pendulum's own scale, then Nelder–Mead; rise plus settling time) to seed the population (or the
    profile's current gains, when it has them, so that a re-run can only improve on them); then a
    seeded differential evolution over the log of (kp, ki, kd, inner kp, ki, kd, integral band) within
    wide physical bounds (``generations`` × ``population`` × 7 evaluations), polished by Nelder–Mead. A
    band as wide as the largest error means "no gating", so the search decides whether the PID uses the
    RSLQR's integrator gating.
    """
    from scipy.optimize import differential_evolution

    if loop not in ("speed", "roll"):
        raise InvalidInput("loop", f"must be 'speed' or 'roll', got {loop!r}")
    rob = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    params = params_from_profile(rob)
    sub = "pitch" if loop == "speed" else "roll"
    evaluations = 0
    tolerance = pitch_tolerance(rob) if loop == "speed" else PITCH_TOLERANCE_RAD

    # 1. the inner loop alone, to seed the search
    j_a, j_s = params.inertias(sub)
    j_eff = (j_a * j_s - params.coupling**2) / j_s
    k_g = params.gravity_torque_n_m
    inner_cache: dict[tuple[float, float, float], float] = {}

    def inner_cost(z: np.ndarray) -> float:
        nonlocal evaluations
        kp, ki, kd = (float(v) for v in np.exp(z))
        key = (round(kp, 5), round(ki, 5), round(kd, 5))
        if key not in inner_cache:
            evaluations += 1
            inner_cache[key] = _inner_objective(inner_step(params, loop, PIDGains(0.0, 0.0, 0.0, kp, ki, kd)), 1.5)
        return inner_cache[key]

    grid_i = itertools.product(
        [k_g * f for f in (0.5, 1.0, 2.0, 4.0)],
        [k_g * f for f in (0.5, 2.0, 8.0)],
        [j_eff * w for w in (2.0, 5.0, 12.0)],
    )
    start_i = min(grid_i, key=lambda g: inner_cost(np.log(np.array(g))))
    inner0, _ = _nelder_mead(inner_cost, np.log(np.array(start_i)), 60)
    log.info("tune %s inner seed: %s", loop, np.round(np.exp(inner0), 3))

    # 2. everything at once on the figure's cases
    unit = 0.5 if loop == "speed" else 1.0  # pendulum set-point (rad) per unit error, order of magnitude
    big_error = 3.0 if loop == "speed" else 1.0
    lo = np.log([unit * 0.05, unit * 0.01, unit * 1e-3, k_g * 0.3, k_g * 0.3, j_eff * 0.5, big_error / 100])
    hi = np.log([unit * 20.0, unit * 20.0, unit * 2.0, k_g * 10.0, k_g * 30.0, j_eff * 50.0, big_error])
    cache: dict[tuple[float, ...], float] = {}

    def gains_of(z: np.ndarray) -> PIDGains:
        g = np.exp(np.clip(z, lo, hi))
        band = None if g[6] >= big_error * 0.999 else float(g[6])
        kp, ki, kd, ikp, iki, ikd = (float(f"{v:.4g}") for v in g[:6])
        return PIDGains(kp, ki, kd, ikp, iki, ikd, integral_band=band)

    def cost(z: np.ndarray) -> float:
        nonlocal evaluations
        g = gains_of(z)
        key = (*g.outer_gains, *g.inner_gains, g.integral_band or 0.0)
        if key not in cache:
            evaluations += 1
            cache[key] = _objective(loop, _pid_cases(rob, loop, g), params, tolerance)
        return cache[key]

    seed_point = np.concatenate([np.log([unit, unit, unit * 0.1]), inner0, [hi[6]]])
    try:  # the profile's current gains join the initial population: a re-run can only improve on them
        known = pid_gains_from_profile(rob, loop)
        seed_point = np.log([*known.outer_gains, *known.inner_gains, known.integral_band or big_error])
    except InvalidInput:
        pass
    res = differential_evolution(
        cost, list(zip(lo, hi, strict=True)), maxiter=generations, popsize=population, seed=seed, tol=0.0,
        polish=False, init="sobol", x0=np.clip(seed_point, lo, hi), updating="immediate",
    )
    log.info("tune %s: differential evolution %.3f after %d evaluations", loop, res.fun, evaluations)
    best, best_cost = np.asarray(res.x), float(res.fun)
    x, f = _nelder_mead(cost, best, polish_iter)
    if f < best_cost:
        best, best_cost = x, f
    gains = gains_of(best)
    cases = _pid_cases(rob, loop, gains)
    return TuneResult(gains, _objective(loop, cases, params, tolerance), cases, evaluations)


@dataclass(frozen=True)
class RSLQRTuneResult:
    """Tuned RSLQR weights, their objective (summed rise time + penalties, s) and each case's metrics."""

    settings: RSLQRSettings
    objective: float
    cases: list[dict[str, Any]]
    evaluations: int


def tune_rslqr(
    robot: RobotProfile | str | None,
    generations: int = 10,
    population: int = 8,
    seed: int = 0,
    base: RSLQRSettings | None = None,
) -> RSLQRTuneResult:
    """Tune the RSLQR's eq. 26 weights the same way as the roll PID (same cases, objective, limits).

    The weights on (∫e, β, β̇, φ − φ_d, φ̇) are searched in log space by the same seeded differential
    evolution (r is fixed at the default: the LQR depends only on the ratios), then polished by
    Nelder–Mead; the default weights are part of the initial population. Designs whose linear loop is
    unstable as sampled at 50 Hz are rejected before simulating: they only "work" by chattering at the
    torque limit (a first unconstrained run found one: ±8 N m at 25 Hz, 0.12 s rise). Both tunings
    also penalise torque chatter once settled (total variation over the last second above the limit).
    """
    from scipy.optimize import differential_evolution

    rob = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    params = params_from_profile(rob)
    base = base or RSLQRSettings()
    lo, hi = np.log([1.0, 0.01, 0.01, 10.0, 1.0]), np.log([1e4, 1e3, 1e3, 1e6, 1e5])
    cache: dict[tuple[float, ...], float] = {}
    evaluations = 0

    def settings_of(z: np.ndarray) -> RSLQRSettings:
        q = tuple(float(f"{v:.4g}") for v in np.exp(np.clip(z, lo, hi)))
        return RSLQRSettings(**{**base.__dict__, "q": q})

    def cases_of(st: RSLQRSettings) -> list[dict[str, Any]]:
        return [
            {k: v for k, v in roll_step(rob, "rslqr", sp, ph, rslqr=st).items() if k != "series"}
            for sp, ph in FIG13_CASES
        ]

    def cost(z: np.ndarray) -> float:
        nonlocal evaluations
        st = settings_of(z)
        if st.q not in cache:
            radius = max(sampled_spectral_radius(params, st, sp) for sp in {0.0, *(c[0] for c in FIG13_CASES)})
            if radius >= 1.0:  # unstable as sampled at 50 Hz: it could only work by chattering in saturation
                cache[st.q] = 100.0 + radius
            else:
                evaluations += 1
                cache[st.q] = _objective("roll", cases_of(st), params)
        return cache[st.q]

    x0 = np.clip(np.log(np.array(base.q)), lo, hi)
    res = differential_evolution(
        cost, list(zip(lo, hi, strict=True)), maxiter=generations, popsize=population, seed=seed, tol=0.0,
        polish=False, init="sobol", x0=x0, updating="immediate",
    )
    best, best_cost = np.asarray(res.x), float(res.fun)
    x, f = _nelder_mead(cost, best, 60)
    if f < best_cost:
        best, best_cost = x, f
    st = settings_of(best)
    cases = cases_of(st)
    return RSLQRTuneResult(st, _objective("roll", cases, params), cases, evaluations)
