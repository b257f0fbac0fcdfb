"""The fastest 10 → 90 % speed rise the pendulum sphere's bounds allow, and where the LMPC and the PID sit.

Run from the repository root (minutes per case on a shared 2-core machine, so it is a script)::

    python -m lab.pendulum.min_rise                    # every Fig. 11 case, zju-60
    python -m lab.pendulum.min_rise --robot zju-80 --case 0.5 tiled

For one case of Fig. 11 (speed V, floor) it solves, with CasADi + IPOPT, the minimum-time problem on
the *nonlinear* pitch model of :mod:`planner.pendulum.dynamics` (the plant's own equations and its
integrator: RK4, 4 substeps per period) under the bounds both controllers obey:

* the torque is held over each 20 ms period (50 Hz, as both controllers), |τ_p| ≤ τ_max;
* the pendulum pitch |α| ≤ 15° + 0.15° (the tolerance the PID's tuning is granted because the LMPC's
  softened bound peaks at 15.13°) at every RK4 substep, not only at the samples;
* the rise is measured exactly as :func:`planner.pendulum.steps.step_metrics` does it (first
  crossings of 10 % and 90 % of V, interpolated between samples);
* no overshoot: after crossing 90 % the speed stays within [0.9 V, V] for the rest of the horizon
  (0.5 s) — both controllers stay within 3 % of V, the LMPC within 0.1 %.

The number of periods between the two crossings is found by bisection (a solve that IPOPT reports
infeasible counts as infeasible, so the answer is an upper bound on the true minimum, within one
solver failure); each solve starts from the LMPC's own run. Output: one row per case with the bound,
the LMPC's and the PID's rise and their distance to the bound. docs/pendulum.md reports the last run.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planner.pendulum.dynamics import G, PendulumParams, PendulumSpherePlant, params_from_profile
from planner.pendulum.steps import FIG11_CASES, PITCH_TOLERANCE_RAD, TS_S, speed_step
from planner.robot import load_robot

SUBSTEPS = 4
TAIL = 25


def _period(params: PendulumParams, c_rr: float):
    """CasADi function (x, u) → (x after one period, the pitch at every substep): the plant's RK4."""
    import casadi as ca

    p = params
    r, l, mp = p.radius_m, p.pendulum_length_m, p.pendulum_mass_kg
    c = mp * r * l
    ja, js = p.inertias("pitch")
    x, u = ca.SX.sym("x", 4), ca.SX.sym("u")

    def f(s):
        a, ad, v = s[0], s[1], s[3]
        fx = c_rr * p.total_mass_kg * G * v / ca.sqrt(v * v + p.rolling_speed_eps_m_s**2)
        rel = p.damping_pitch_n_m_s * (ad + v / r)
        qa = u - mp * G * l * ca.sin(a) - rel
        qs = u - rel + c * ad * ad * ca.sin(a) - r * fx
        m12 = c * ca.cos(a)
        det = ja * js - m12 * m12
        return ca.vertcat(ad, (js * qa - m12 * qs) / det, v, r * (ja * qs - m12 * qa) / det)

    h = TS_S / SUBSTEPS
    s, alphas = x, []
    for _ in range(SUBSTEPS):
        k1 = f(s)
        k2 = f(s + h / 2 * k1)
        k3 = f(s + h / 2 * k2)
        k4 = f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        alphas.append(s[0])
    return ca.Function("period", [x, u], [s, ca.vertcat(*alphas)])


def _solve(params, c_rr, speed, i10, d, u0, x0):
    """Minimum interpolated rise with the 10 % crossing in period i10 and the 90 % one d periods later."""
    import casadi as ca

    period = _period(params, c_rr)
    n = i10 + d + 1 + TAIL
    opti = ca.Opti()
    u = opti.variable(n)
    x = opti.variable(4, n + 1)
    opti.subject_to(x[:, 0] == 0)
    amax = params.max_pendulum_angle_rad + PITCH_TOLERANCE_RAD
    for k in range(n):
        nxt, alphas = period(x[:, k], u[k])
        opti.subject_to(x[:, k + 1] == nxt)
        opti.subject_to(opti.bounded(-amax, alphas, amax))
    tmax = params.max_torque_pitch_n_m
    opti.subject_to(opti.bounded(-tmax, u, tmax))
    v = x[3, :]
    i90 = i10 + d
    opti.subject_to(v[: i10 + 1] <= 0.1 * speed)
    opti.subject_to(v[i10 + 1] >= 0.1 * speed + 1e-4)
    opti.subject_to(v[: i90 + 1] <= 0.9 * speed)
    opti.subject_to(v[i90 + 1] >= 0.9 * speed + 1e-4)
    opti.subject_to(opti.bounded(0.9 * speed, v[i90 + 1 :], speed))
    t10 = TS_S * (i10 + (0.1 * speed - v[i10]) / (v[i10 + 1] - v[i10]))
    t90 = TS_S * (i90 + (0.9 * speed - v[i90]) / (v[i90 + 1] - v[i90]))
    opti.minimize(t90 - t10)
    opti.set_initial(u, u0[:n])
    opti.set_initial(x, x0[:, : n + 1])
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "max_iter": 1500, "tol": 1e-9})
    try:
        sol = opti.solve()
    except RuntimeError:
        return None
    return float(sol.value(t90 - t10))


def min_rise(robot: str, speed: float, floor: str) -> dict[str, float | int]:
    rob = load_robot(robot)
    params = params_from_profile(rob)
    c_rr = params.floor_coefficient(floor)
    lmpc = speed_step(rob, "lmpc", speed, floor, duration_s=12.0)
    pid = speed_step(rob, "pid", speed, floor)
    v = np.array([s["v"] for s in lmpc["series"]])
    u0 = np.array([s["torque"] for s in lmpc["series"]])
    plant = PendulumSpherePlant(params, floor)
    s, xs = np.zeros(11), [np.zeros(4)]
    for tau in u0:
        s = plant.step(s, float(tau), 0.0, TS_S)
        xs.append(s[:4].copy())
    x0 = np.array(xs).T
    i10 = int(np.flatnonzero(v >= 0.1 * speed)[0]) - 1
    hi = int(np.flatnonzero(v >= 0.9 * speed)[0]) - 1 - i10  # the LMPC's own window: feasible
    best = _solve(params, c_rr, speed, i10, hi, u0, x0)
    lo = int(hi * 0.6)  # infeasible: the pendulum cannot accelerate that much faster
    while hi - lo > 1:
        mid = (lo + hi) // 2
        res = _solve(params, c_rr, speed, i10, mid, u0, x0)
        if res is None:
            lo = mid
        else:
            hi, best = mid, res
    assert best is not None
    return {
        "speed_m_s": speed, "floor": floor, "bound_s": best, "periods": hi,
        "lmpc_s": float(lmpc["rise_time_s"]), "pid_s": float(pid["rise_time_s"]),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", default="zju-60")
    ap.add_argument("--case", nargs=2, metavar=("SPEED", "FLOOR"), help="one case (default: every Fig. 11 case)")
    args = ap.parse_args(argv)
    cases = [(float(args.case[0]), args.case[1])] if args.case else list(FIG11_CASES)
    print(f"{'case':16} {'bound s':>8} {'LMPC s':>8} {'PID s':>8} {'LMPC−bound':>10} {'PID−bound':>10} {'wall s':>7}")
    for speed, floor in cases:
        t0 = time.perf_counter()
        r = min_rise(args.robot, speed, floor)
        print(
            f"{speed} m/s {floor:8} {r['bound_s']:8.3f} {r['lmpc_s']:8.3f} {r['pid_s']:8.3f} "
            f"{r['lmpc_s'] - r['bound_s']:10.3f} {r['pid_s'] - r['bound_s']:10.3f} {time.perf_counter() - t0:7.0f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
