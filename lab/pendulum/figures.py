"""Every case of paper 001's Figs. 11 and 13 with both controllers, as a summary table."""

from __future__ import annotations

import math
from typing import Any

from planner.pendulum.dynamics import params_from_profile
from planner.pendulum.steps import (
    FIG11_CASES,
    FIG13_CASES,
    ROLL_CONTROLLERS,
    SPEED_CONTROLLERS,
    max_steady_roll,
    roll_step,
    speed_step,
)
from planner.robot import RobotProfile, load_robot


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
