"""MPC step times in closed loop (``sphereplan bench --suite mpc``): the tracker of paper 001 eq. 15 on an
S-curve, per horizon and QP solver."""

from __future__ import annotations

from typing import Any

import numpy as np

from planner.closed_loop.simulate import SimulationOptions, simulate_plan
from planner.closed_loop.tracker import MPCParams
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot


def bench_mpc(
    robot: str = "zju-60",
    horizons: tuple[int, ...] = (10, 15, 20),
    steps: int = 250,
    qpsols: tuple[str, ...] = ("qrqp",),
) -> list[dict[str, Any]]:
    """Time the MPC step in closed loop on an S-curve (noise-free): one row per (horizon, QP solver) with
    solve-time percentiles in ms. ``steps`` control periods per row. Prints nothing; see the CLI."""
    from planner.synthetic_paths import s_curve_plan

    rob = load_robot(robot)
    plan = s_curve_plan(rob)
    grid = OccupancyGrid.from_occupied(np.zeros((120, 160), dtype=bool), 0.05, (-1.0, -2.0, 0.0))
    rows = []
    for qp in qpsols:
        for n in horizons:
            opts = SimulationOptions(mpc=MPCParams(horizon=n, qpsol=qp), time_limit_s=steps / 50.0)
            m = simulate_plan(grid, plan, rob, seed=0, noise="none", options=opts)["metrics"]
            rows.append(
                {
                    "robot": robot,
                    "qpsol": qp,
                    "horizon": n,
                    "steps": m["steps"],
                    "p50_ms": m["mpc_solve_ms_p50"],
                    "p95_ms": m["mpc_solve_ms_p95"],
                    "fallback_steps": m["fallback_steps"],
                }
            )
    return rows



def format_mpc_bench(rows: list[dict[str, Any]]) -> str:
    """The rows of :func:`bench_mpc` as a table (MPC step time per horizon)."""
    lines = [f"{'robot':8} {'qpsol':6} {'N':>3} {'steps':>6} {'p50 ms':>8} {'p95 ms':>8} {'fallback':>8}"]
    for r in rows:
        lines.append(f"{r['robot']:8} {r['qpsol']:6} {r['horizon']:>3} {r['steps']:>6} {r['p50_ms']:>8.2f} "
                     f"{r['p95_ms']:>8.2f} {r['fallback_steps']:>8}")
    return "\n".join(lines)
