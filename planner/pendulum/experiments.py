"""Paper 001's motion-control experiments (§6.6–6.7, Figs. 11–13) on the dynamic plant, and PID tuning.

* :func:`speed_step` — Figs. 11–12: from rest to a speed V on a floor (``tiled`` / ``rubber``), under the
  LMPC (eq. 20–25) or the PID; velocity, pendulum pitch and torque over time.
* :func:`roll_step` — Fig. 13: rolling straight at V (speed held by the LMPC in both cases), a roll step
  to φ_d at t = 0 under the RSLQR (eq. 26–32) or the PID.
* :func:`step_metrics` — rise time (10 → 90 % of the step, crossings interpolated between samples),
  overshoot (fraction of the step), settling time (last exit from a ±5 % band) and steady-state error
  (mean over the last second).
* :func:`tune_pid` — how the baselines were tuned (docs/pendulum.md): all gains of the double-loop PID
  by a seeded differential evolution + Nelder–Mead, minimising the PID's summed rise time over every
  case of its figure subject to the limits the model-based controller meets on the same cases
  (overshoot ≤ 10 %, settled within ±5 % before the run ends, steady-state error ≤ 2 % of the step, no
  torque chatter once settled); :func:`tune_rslqr` tunes the RSLQR's weights the same way.
* :func:`run_figures` — every case of Figs. 11 and 13 with both controllers; :func:`bench_controllers` —
  controller step times.

All runs are deterministic (no noise); the plant is integrated with RK4, 4 substeps per 20 ms period.
"""

from __future__ import annotations

import itertools
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.pendulum.dynamics import IA, IB, IPHI, IV, PendulumParams, PendulumSpherePlant, params_from_profile
from planner.pendulum.lmpc import LMPCSettings, LMPCSpeedController
from planner.pendulum.pid import PIDController, PIDGains, pid_gains_from_profile, setpoint_limit
from planner.pendulum.rslqr import RSLQRRollController, RSLQRSettings, sampled_spectral_radius
from planner.robot import RobotProfile, load_robot

log = logging.getLogger(__name__)

TS_S = 0.02
"""Control period (paper 001 §5: 50 Hz)."""

FIG11_CASES: tuple[tuple[float, str], ...] = ((0.5, "tiled"), (1.5, "tiled"), (0.5, "rubber"), (1.5, "rubber"))
"""Fig. 11 (a)–(d): (speed m/s, floor)."""

FIG13_CASES: tuple[tuple[float, float], ...] = ((0.5, 0.12), (1.0, 0.12), (1.0, 0.19))
"""Fig. 13 (a)–(c): (speed m/s, desired roll rad)."""

SPEED_DURATION_S = 8.0
ROLL_DURATION_S = 4.0
ROLL_SETTLE_S = 1.0
SETTLE_BAND = 0.05
MAX_OVERSHOOT = 0.10
MAX_STEADY_ERROR = 0.02
PITCH_TOLERANCE_RAD = math.radians(0.15)  # zju-60's LMPC itself peaks at 15.13° (see pitch_tolerance)
MAX_TAIL_VARIATION = 1.0  # torque total variation over the last second, in units of the torque limit

SPEED_CONTROLLERS = ("lmpc", "pid")
ROLL_CONTROLLERS = ("rslqr", "pid")


def step_metrics(
    t: np.ndarray, y: np.ndarray, y0: float, ref: float, band: float = SETTLE_BAND, tail_s: float = 1.0
) -> dict[str, float | None]:
    """Step-response figures of ``y(t)`` for a step from ``y0`` to ``ref`` at t = t[0].

    rise_time_s: first time y passes 90 % of the step minus the first time it passes 10 % (None if it
    never reaches 90 %), each crossing interpolated linearly between the two samples around it (the
    runs are sampled at the 50 Hz control rate; a first-sample crossing would quantise the rise time to
    0.02 s and make two controllers within one period "tie"); overshoot: how far y goes past ``ref``, as
    a fraction of the step (≥ 0); settling_time_s: time after which y stays within ±``band`` of the step
    around ``ref`` (None if the last sample is outside); steady_state_error: |ref − mean of y over the
    last ``tail_s``| (units of y).
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    step = ref - y0
    if step == 0:
        raise InvalidInput("ref", "the step must change the reference")
    frac = (y - y0) / step
    t10, t90 = crossing_time(t, frac, 0.1), crossing_time(t, frac, 0.9)
    rise = None if t10 is None or t90 is None else t90 - t10
    overshoot = max(0.0, float(frac.max()) - 1.0)
    outside = np.flatnonzero(np.abs(frac - 1.0) > band)
    if len(outside) == 0:
        settling: float | None = 0.0
    elif outside[-1] == len(t) - 1:
        settling = None
    else:
        settling = float(t[outside[-1] + 1] - t[0])
    tail = t >= t[-1] - tail_s + 1e-9
    sse = abs(ref - float(np.mean(y[tail])))
    return {
        "rise_time_s": rise,
        "overshoot": overshoot,
        "settling_time_s": settling,
        "steady_state_error": sse,
    }


def crossing_time(t: np.ndarray, frac: np.ndarray, level: float) -> float | None:
    """First time ``frac`` reaches ``level``, interpolated linearly between the samples around it
    (None if it never does; t[0] if it starts there)."""
    above = np.flatnonzero(frac >= level)
    if len(above) == 0:
        return None
    i = int(above[0])
    if i == 0:
        return float(t[0])
    f0, f1 = float(frac[i - 1]), float(frac[i])
    return float(t[i - 1] + (level - f0) / (f1 - f0) * (t[i] - t[i - 1]))


def _tail_variation(tau: np.ndarray, tail_s: float = 1.0) -> float:
    """Total variation of the torque over the last ``tail_s`` (N m): ≈ 0 once settled, large for chatter."""
    n = int(round(tail_s / TS_S)) + 1
    return float(np.abs(np.diff(tau[-n:])).sum())


def _check_speed(params: PendulumParams, speed: float) -> None:
    if not (math.isfinite(speed) and speed != 0 and abs(speed) <= params.max_speed_m_s):
        raise InvalidInput("speed", f"must be non-zero with |speed| <= {params.max_speed_m_s} m/s, got {speed!r}")


def _speed_controller(
    robot: RobotProfile, params: PendulumParams, controller: str, gains: PIDGains | None, lmpc: LMPCSettings | None
) -> Callable[[np.ndarray, float], float]:
    if controller == "lmpc":
        c = LMPCSpeedController(params, lmpc)
        return c.step
    if controller == "pid":
        pid = PIDController(
            gains or pid_gains_from_profile(robot, "speed"),
            params.max_torque_pitch_n_m,
            setpoint_limit(params, "speed"),
            TS_S,
        )
        return lambda y, v_ref: pid.step(v_ref, float(y[3]), float(y[0]), float(y[1]))
    raise InvalidInput("controller", f"must be one of {', '.join(SPEED_CONTROLLERS)}, got {controller!r}")


def speed_step(
    robot: RobotProfile | str | None,
    controller: str,
    speed: float,
    floor: str | None = None,
    duration_s: float = SPEED_DURATION_S,
    gains: PIDGains | None = None,
    lmpc: LMPCSettings | None = None,
) -> dict[str, Any]:
    """Figs. 11–12: start from rest, step the speed reference to ``speed``; the result JSON."""
    rob = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    params = params_from_profile(rob)
    _check_speed(params, speed)
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise InvalidInput("duration", f"must be a finite number > 0, got {duration_s!r}")
    plant = PendulumSpherePlant(params, floor)
    ctrl = _speed_controller(rob, params, controller, gains, lmpc)
    s = np.zeros(11)
    rows = []
    for k in range(int(round(duration_s / TS_S)) + 1):
        tau = ctrl(s[0:4], speed)
        rows.append((k * TS_S, float(s[IV]), speed, float(s[IA]), tau))
        s = plant.step(s, tau, 0.0, TS_S)
    arr = np.array(rows)
    m = step_metrics(arr[:, 0], arr[:, 1], 0.0, speed)
    return {
        "experiment": "speed_step",
        "robot": rob.name,
        "controller": controller,
        "floor": plant.floor,
        "speed_m_s": speed,
        "control_rate_hz": 1.0 / TS_S,
        **m,
        "max_pitch_rad": float(np.abs(arr[:, 3]).max()),
        "max_torque_n_m": float(np.abs(arr[:, 4]).max()),
        "torque_variation_last_s_n_m": _tail_variation(arr[:, 4]),
        "series": [
            {"t": round(r[0], 4), "v": round(r[1], 6), "v_ref": r[2], "pitch": round(r[3], 6), "torque": round(r[4], 5)}
            for r in rows
        ],
    }


def roll_step(
    robot: RobotProfile | str | None,
    controller: str,
    speed: float,
    roll: float,
    duration_s: float = ROLL_DURATION_S,
    gains: PIDGains | None = None,
    rslqr: RSLQRSettings | None = None,
    settle_s: float = ROLL_SETTLE_S,
) -> dict[str, Any]:
    """Fig. 13: roll straight at ``speed`` (LMPC), step the roll reference to ``roll`` at t = 0."""
    rob = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    params = params_from_profile(rob)
    _check_speed(params, speed)
    if not (math.isfinite(roll) and roll != 0 and abs(roll) <= rob.max_roll_rad + 1e-12):
        raise InvalidInput(
            "roll", f"must be non-zero with |roll| <= {rob.max_roll_rad:.4f} rad (the profile's max roll), got {roll!r}"
        )
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise InvalidInput("duration", f"must be a finite number > 0, got {duration_s!r}")
    plant = PendulumSpherePlant(params)
    speed_ctrl = LMPCSpeedController(params)
    if controller == "rslqr":
        lqr = RSLQRRollController(params, rslqr)
        roll_ctrl: Callable[[np.ndarray, float, float], float] = lqr.step
    elif controller == "pid":
        pid = PIDController(
            gains or pid_gains_from_profile(rob, "roll"),
            params.max_torque_roll_n_m,
            setpoint_limit(params, "roll"),
            TS_S,
        )
        roll_ctrl = lambda x, ref, v: pid.step(ref, float(x[2]), float(x[0]), float(x[1]))  # noqa: E731
    else:
        raise InvalidInput("controller", f"must be one of {', '.join(ROLL_CONTROLLERS)}, got {controller!r}")
    s = plant.rolling_state(speed)
    rows = []
    n_pre = int(round(settle_s / TS_S))
    for k in range(n_pre + int(round(duration_s / TS_S)) + 1):
        t = (k - n_pre) * TS_S
        ref = roll if k >= n_pre else 0.0
        tau_p = speed_ctrl.step(s[0:4], speed)
        tau_r = roll_ctrl(s[4:8], ref, float(s[IV]))
        if k >= n_pre:
            rows.append((t, float(s[IPHI]), ref, float(s[IB]), tau_r, float(s[IV])))
        s = plant.step(s, tau_p, tau_r, TS_S)
    arr = np.array(rows)
    m = step_metrics(arr[:, 0], arr[:, 1], float(arr[0, 1]), roll)
    return {
        "experiment": "roll_step",
        "robot": rob.name,
        "controller": controller,
        "floor": plant.floor,
        "speed_m_s": speed,
        "roll_rad": roll,
        "control_rate_hz": 1.0 / TS_S,
        **m,
        "max_pendulum_roll_rad": float(np.abs(arr[:, 3]).max()),
        "max_torque_n_m": float(np.abs(arr[:, 4]).max()),
        "torque_variation_last_s_n_m": _tail_variation(arr[:, 4]),
        "series": [
            {
                "t": round(r[0], 4),
                "roll": round(r[1], 6),
                "roll_ref": r[2],
                "pendulum_roll": round(r[3], 6),
                "torque": round(r[4], 5),
                "v": round(r[5], 6),
            }
            for r in rows
        ],
    }


def max_steady_roll(params: PendulumParams, speed: float) -> float:
    """Largest roll (rad) the auxiliary motor can hold in a steady turn at ``speed``.

    The steady turn needs τ_r = (m + I_s/r²) v² tan φ (see :mod:`planner.pendulum.rslqr`), so
    tan φ_max = τ_max / ((m + I_s/r²) v²): the faster the robot rolls, the smaller the roll it can hold.
    """
    k = (params.total_mass_kg + params.shell_inertia_kg_m2 / params.radius_m**2) * speed * speed
    return math.pi / 2 if k == 0 else math.atan(params.max_torque_roll_n_m / k)


# ---------------------------------------------------------------- PID tuning


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


# ---------------------------------------------------------------- figures and benchmark


def run_figures(robot: RobotProfile | str | None = None) -> dict[str, Any]:
    """Every case of Fig. 11 (both speed controllers) and Fig. 13 (both roll controllers), full results."""
    rob = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    fig11 = [
        {c: speed_step(rob, c, sp, fl) for c in SPEED_CONTROLLERS}
        for sp, fl in FIG11_CASES
    ]
    fig13 = [
        {c: roll_step(rob, c, sp, ph) for c in ROLL_CONTROLLERS}
        for sp, ph in FIG13_CASES
    ]
    params = params_from_profile(rob)
    return {
        "robot": rob.name,
        "fig11": fig11,
        "fig13": fig13,
        "max_steady_roll_rad": {f"{v:.1f}": max_steady_roll(params, v) for v in (0.5, 1.0, 1.5, 2.0)},
    }


def summary_rows(figs: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per case and controller: the step figures without the time series."""
    rows = []
    for group in ("fig11", "fig13"):
        for case in figs[group]:
            for name, res in case.items():
                row = {k: v for k, v in res.items() if k != "series"}
                row["figure"] = group
                row["controller"] = name
                rows.append(row)
    return rows


def format_summary(figs: dict[str, Any]) -> str:
    """Figs. 11 and 13 as a table: rise time, overshoot, settling, steady error, pendulum angle."""
    lines = [
        f"{'fig':5} {'case':22} {'controller':10} {'rise s':>7} {'overshoot':>9} {'settle s':>8} "
        f"{'ss err':>8} {'pend. max °':>11}"
    ]

    def num(x: float | None, fmt: str) -> str:
        return "-" if x is None else format(x, fmt)

    for row in summary_rows(figs):
        if row["figure"] == "fig11":
            case = f"{row['speed_m_s']} m/s {row['floor']}"
            pend = row["max_pitch_rad"]
        else:
            case = f"{row['speed_m_s']} m/s, {row['roll_rad']} rad"
            pend = row["max_pendulum_roll_rad"]
        lines.append(
            f"{row['figure']:5} {case:22} {row['controller']:10} {num(row['rise_time_s'], '7.3f')} "
            f"{100 * row['overshoot']:8.1f}% {num(row['settling_time_s'], '8.2f')} "
            f"{row['steady_state_error']:8.4f} {math.degrees(pend):11.1f}"
        )
    return "\n".join(lines)


def bench_controllers(robot: RobotProfile | str | None = None, steps: int = 300) -> list[dict[str, Any]]:
    """Time one control step of each controller (and one plant period) over a Fig. 11/13 run, in µs."""
    from planner.pendulum.qp import QP_SOLVERS

    rob = robot if isinstance(robot, RobotProfile) else load_robot(robot)
    params = params_from_profile(rob)
    rows = []

    def record(name: str, samples: list[float]) -> None:
        arr = np.array(samples) * 1e6
        rows.append({
            "robot": rob.name, "controller": name, "steps": len(arr),
            "p50_us": float(np.percentile(arr, 50)), "p95_us": float(np.percentile(arr, 95)),
            "max_us": float(arr.max()),
        })

    plant = PendulumSpherePlant(params)
    for qpsol in QP_SOLVERS:
        ctrl = LMPCSpeedController(params, LMPCSettings(qpsol=qpsol))
        s, times = np.zeros(11), []
        for _ in range(steps):
            t0 = time.perf_counter()
            tau = ctrl.step(s[0:4], 1.5)
            times.append(time.perf_counter() - t0)
            s = plant.step(s, tau, 0.0, TS_S)
        record(f"lmpc ({qpsol})", times)
    pid = PIDController(
        pid_gains_from_profile(rob, "speed"), params.max_torque_pitch_n_m, setpoint_limit(params, "speed"), TS_S
    )
    s, times = np.zeros(11), []
    for _ in range(steps):
        t0 = time.perf_counter()
        tau = pid.step(1.5, float(s[IV]), float(s[IA]), float(s[1]))
        times.append(time.perf_counter() - t0)
        s = plant.step(s, tau, 0.0, TS_S)
    record("pid (speed)", times)
    for name in ROLL_CONTROLLERS:
        lqr = RSLQRRollController(params)
        rpid = PIDController(
            pid_gains_from_profile(rob, "roll"), params.max_torque_roll_n_m, setpoint_limit(params, "roll"), TS_S
        )
        s, times = plant.rolling_state(1.0), []
        plant_times = []
        for _ in range(steps):
            t0 = time.perf_counter()
            if name == "rslqr":
                tau_r = lqr.step(s[4:8], 0.19, float(s[IV]))
            else:
                tau_r = rpid.step(0.19, float(s[IPHI]), float(s[IB]), float(s[5]))
            times.append(time.perf_counter() - t0)
            t1 = time.perf_counter()
            s = plant.step(s, 2.0, tau_r, TS_S)
            plant_times.append(time.perf_counter() - t1)
        record(f"{name} (roll)", times)
    record("plant period (RK4 x4)", plant_times)
    return rows


def format_bench(rows: list[dict[str, Any]]) -> str:
    lines = [f"{'robot':7} {'controller':22} {'steps':>6} {'p50 µs':>9} {'p95 µs':>9} {'max µs':>9}"]
    for r in rows:
        lines.append(
            f"{r['robot']:7} {r['controller']:22} {r['steps']:>6} {r['p50_us']:>9.1f} {r['p95_us']:>9.1f} "
            f"{r['max_us']:>9.1f}"
        )
    return "\n".join(lines)


__all__ = [
    "FIG11_CASES",
    "FIG13_CASES",
    "RSLQRTuneResult",
    "TuneResult",
    "bench_controllers",
    "crossing_time",
    "format_bench",
    "format_summary",
    "max_steady_roll",
    "roll_step",
    "run_figures",
    "speed_step",
    "step_metrics",
    "summary_rows",
    "tune_pid",
    "tune_rslqr",
]
