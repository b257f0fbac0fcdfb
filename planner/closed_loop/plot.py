"""Picture of one closed-loop simulation: the map with the planned path and the true, fused and
odometry-only trajectories (paper 001 Fig. 7 style), next to the errors and commands over time."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from planner.closed_loop.simulate import cross_track_distance
from planner.occupancy import OccupancyGrid


def plot_simulation(
    grid: OccupancyGrid, plan_json: dict[str, Any], sim: dict[str, Any], out: str | Path
) -> None:
    """Write a PNG of ``sim`` (a :func:`~planner.closed_loop.simulate.simulate_plan` result) over ``grid``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = np.array([[s["x"], s["y"]] for s in plan_json["states"]])
    tr = np.array([[r["t"], r["x"], r["y"]] for r in sim["trajectory"]])
    es = np.array([[r["x"], r["y"]] for r in sim["estimate"]])
    od = np.array([[r["x"], r["y"]] for r in sim["odometry"]])
    gn = np.array([[r["x"], r["y"]] for r in sim["gnss"]]).reshape(-1, 2)
    cmd = np.array([[r["t"], r["v"], r["roll"]] for r in sim["commands"]]).reshape(-1, 3)
    m = sim["metrics"]

    fig = plt.figure(figsize=(13, 7), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=(1.6, 1))
    ax = fig.add_subplot(gs[:, 0])
    ox, oy, _ = grid.origin
    w, h = grid.size_m
    ax.imshow(
        np.where(grid.blocked(), 0.15, 1.0),
        cmap="gray",
        vmin=0,
        vmax=1,
        origin="lower",
        extent=(ox, ox + w, oy, oy + h),
        interpolation="nearest",
    )
    if len(gn):
        ax.plot(gn[:, 0], gn[:, 1], ".", color="0.6", ms=2, label="GNSS fixes")
    ax.plot(path[:, 0], path[:, 1], "k--", lw=1.2, label="planned path")
    ax.plot(od[:, 0], od[:, 1], ":", color="tab:red", lw=1.5, label="wheel odometry (eq. 2)")
    ax.plot(es[:, 0], es[:, 1], "-", color="tab:green", lw=1.2, label="fused estimate (eq. 3)")
    ax.plot(tr[:, 1], tr[:, 2], "-", color="tab:blue", lw=1.0, label="true trajectory")
    ax.plot(path[0, 0], path[0, 1], "o", color="k", ms=5)
    ax.plot(path[-1, 0], path[-1, 1], "*", color="k", ms=9)
    pad = 1.0
    pts = np.vstack([path, tr[:, 1:3], od])
    ax.set_xlim(max(ox, pts[:, 0].min() - pad), min(ox + w, pts[:, 0].max() + pad))
    ax.set_ylim(max(oy, pts[:, 1].min() - pad), min(oy + h, pts[:, 1].max() + pad))
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(
        f"{sim['robot']['name']} · {sim['tracker']} · noise {sim['noise']} · seed {sim['seed']}\n"
        f"cross-track rms {m['cross_track_rms_m'] * 100:.1f} cm, max {m['cross_track_max_m'] * 100:.1f} cm · "
        f"final error {m['final_position_error_m'] * 100:.1f} cm · clearance {m['min_clearance_m']:.2f} m"
        + (" · COLLIDED" if m["collided"] else ""),
        fontsize=9,
    )

    ae = fig.add_subplot(gs[0, 1])
    ae.plot(
        tr[:, 0], cross_track_distance(path, tr[:, 1:3]) * 100, color="tab:blue", label="cross-track (true)"
    )
    ae.plot(tr[:, 0], np.hypot(*(es - tr[:, 1:3]).T) * 100, color="tab:green", label="fused estimate error")
    ae.plot(tr[:, 0], np.hypot(*(od - tr[:, 1:3]).T) * 100, ":", color="tab:red", label="odometry error")
    ae.set_ylabel("error (cm)")
    ae.set_yscale("symlog", linthresh=1.0)
    ae.legend(fontsize=8)
    ae.grid(alpha=0.3)

    ac = fig.add_subplot(gs[1, 1], sharex=ae)
    ac.plot(cmd[:, 0], cmd[:, 1], color="tab:purple", label="v command (m/s)")
    ac.set_ylabel("v (m/s)")
    ac.set_xlabel("t (s)")
    ar = ac.twinx()
    ar.plot(cmd[:, 0], np.degrees(cmd[:, 2]), color="tab:orange", lw=0.8, label="roll command (°)")
    ar.set_ylabel("roll (°)")
    ac.legend(loc="upper left", fontsize=8)
    ar.legend(loc="upper right", fontsize=8)
    ac.grid(alpha=0.3)
    fig.savefig(out, dpi=110)
    plt.close(fig)
