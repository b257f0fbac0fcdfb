"""Picture of a VPIP schedule: rod-length heat map over time, roll and plane angles, tracked path."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np


def plot_schedule(result: Mapping[str, Any], out: str | Path, plan: Mapping[str, Any] | None = None) -> None:
    """Write a PNG of ``result`` (from :func:`planner.vpip.cascade.run_schedule`) to ``out``.

    Panels: the 16 commanded rod lengths as a heat map (rods × time); desired and simulated roll with
    φ_VPIP; θ_VPIP with desired and simulated ω; the planned and tracked paths (x–y, metres).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = result["series"]
    t = np.asarray(s["t"])
    rods = np.asarray(s["rod_length_m"]).T
    deg = np.degrees
    fig = plt.figure(figsize=(12, 9), constrained_layout=True)
    grid = fig.add_gridspec(3, 2, width_ratios=[2.2, 1])
    ax_rod = fig.add_subplot(grid[0, 0])
    ax_roll = fig.add_subplot(grid[1, 0], sharex=ax_rod)
    ax_pitch = fig.add_subplot(grid[2, 0], sharex=ax_rod)
    ax_xy = fig.add_subplot(grid[:, 1])
    n = rods.shape[0]
    img = ax_rod.imshow(
        rods,
        aspect="auto",
        origin="lower",
        interpolation="nearest",
        cmap="viridis",
        extent=(float(t[0]), float(t[-1]), -0.5, n - 0.5),
        vmin=0.0,
        vmax=float(result["params"]["l_max"]),
    )
    ax_rod.axhline(n / 2 - 0.5, color="white", lw=0.8)
    ax_rod.set_yticks([n / 4 - 0.5, 3 * n / 4 - 0.5], ["left ring", "right ring"])
    ax_rod.set_title(
        f"commanded rod lengths ({result['driver']} driver, rate-limited to "
        f"{result['params']['rod_speed_m_s']} m/s)"
    )
    fig.colorbar(img, ax=ax_rod, label="length (m)", pad=0.01)
    ax_roll.plot(t, deg(s["roll_desired_rad"]), "k--", lw=1.2, label="desired roll")
    ax_roll.plot(t, deg(s["roll_rad"]), "C0", lw=1.5, label="roll (surrogate plant)")
    ax_roll.plot(t, deg(s["phi_vpip_rad"]), "C3", lw=1.0, label="φ_VPIP")
    ax_roll.set_ylabel("deg")
    ax_roll.legend(loc="upper right", fontsize=8)
    ax_roll.grid(alpha=0.3)
    ax_pitch.plot(t, deg(s["theta_vpip_rad"]), "C2", lw=1.0, label="θ_VPIP (deg)")
    ax_w = ax_pitch.twinx()
    ax_w.plot(t, s["omega_desired_rad_s"], "k--", lw=1.2, label="desired ω")
    ax_w.plot(t, s["omega_rad_s"], "C1", lw=1.5, label="ω (surrogate plant)")
    ax_w.set_ylabel("ω (rad/s)")
    ax_pitch.set_ylabel("θ_VPIP (deg)")
    ax_pitch.set_xlabel("time (s)")
    lines = ax_pitch.get_lines() + ax_w.get_lines()
    ax_pitch.legend(lines, [str(line.get_label()) for line in lines], loc="upper right", fontsize=8)
    ax_pitch.grid(alpha=0.3)
    if plan is not None:
        xs = [st["x"] for st in plan["states"]]
        ys = [st["y"] for st in plan["states"]]
        ax_xy.plot(xs, ys, "k--", lw=1.2, label="planned")
    ax_xy.plot(s["x"], s["y"], "C0", lw=1.5, label="tracked (surrogate)")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set_xlabel("x (m)")
    ax_xy.set_ylabel("y (m)")
    ax_xy.legend(fontsize=8)
    ax_xy.grid(alpha=0.3)
    summ = result["summary"]
    ax_xy.set_title(f"max lateral error {summ['max_lateral_error_m']:.2f} m")
    fig.suptitle(f"VPIP schedule — {result['robot']} — surrogate plant, not rod physics")
    fig.savefig(out, dpi=90)
    plt.close(fig)
