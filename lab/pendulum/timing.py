"""Timing of one control step of each pendulum-sphere controller (``sphereplan controllers bench``)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from planner.pendulum.dynamics import IA, IB, IPHI, IV, PendulumSpherePlant, params_from_profile
from planner.pendulum.lmpc import LMPCSettings, LMPCSpeedController
from planner.pendulum.pid import PIDController, pid_gains_from_profile, setpoint_limit
from planner.pendulum.rslqr import RSLQRRollController
from planner.pendulum.steps import ROLL_CONTROLLERS, TS_S
from planner.robot import RobotProfile, load_robot


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

