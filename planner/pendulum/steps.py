"""Paper 001's step experiments on the pendulum sphere's dynamic plant (§6.6–6.7, Figs. 11–13).

* :func:`speed_step` — Figs. 11–12: from rest to a speed V on a floor (``tiled`` / ``rubber``), under the
  LMPC (eq. 20–25) or the PID; velocity, pendulum pitch and torque over time.
* :func:`roll_step` — Fig. 13: rolling straight at V (speed held by the LMPC in both cases), a roll step
  to φ_d at t = 0 under the RSLQR (eq. 26–32) or the PID.
* :func:`step_metrics` — rise time (10 → 90 % of the step, crossings interpolated between samples),
  overshoot (fraction of the step), settling time (last exit from a ±5 % band) and steady-state error
  (mean over the last second).

These are what ``sphereplan controllers step|roll`` run. The tuning, the figure sets and the timing bench built
on them live in the lab (:mod:`lab.pendulum`). All runs are deterministic (no noise); the plant is integrated
with RK4, 4 substeps per 20 ms period.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.pendulum.dynamics import IA, IB, IPHI, IV, PendulumParams, PendulumSpherePlant, params_from_profile
from planner.pendulum.lmpc import LMPCSettings, LMPCSpeedController
from planner.pendulum.pid import PIDController, PIDGains, pid_gains_from_profile, setpoint_limit
from planner.pendulum.rslqr import RSLQRRollController, RSLQRSettings
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
