"""Picture of a VPIP schedule: rod-length heat map over time, roll and plane angles, tracked path."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np


def _rod_heatmap(fig: Any, ax_rod: Any, t: np.ndarray, rods: np.ndarray, l_max: float) -> None:
    """The 16 rod lengths over time: one row per rod, numbered, the two rings named on the right."""
    n = rods.shape[0]
    img = ax_rod.imshow(rods, aspect="auto", origin="lower", interpolation="nearest", cmap="viridis",
                        extent=(float(t[0]), float(t[-1]), -0.5, n - 0.5), vmin=0.0, vmax=l_max)
    ax_rod.axhline(n / 2 - 0.5, color="white", lw=0.8)
    ax_rod.set_yticks(range(n), [str(k) for k in range(n)], fontsize=7)
    ax_rod.set_ylabel("rod number")
    ring = ax_rod.secondary_yaxis("right")
    ring.set_yticks([n / 4 - 0.5, 3 * n / 4 - 0.5], [f"left ring\n(0–{n // 2 - 1})", f"right ring\n({n // 2}–{n - 1})"])
    ring.tick_params(length=0, labelsize=8)
    fig.colorbar(img, ax=ax_rod, label="rod length (m)", pad=0.04)


def schedule_figure(result: Mapping[str, Any], plan: Mapping[str, Any] | None = None) -> Any:
    """The figure :func:`plot_schedule` writes (style: :mod:`planner.plotstyle`)."""
    from planner import plotstyle as ps

    plt = ps.pyplot()
    s = result["series"]
    t = np.asarray(s["t"])
    rods = np.asarray(s["rod_length_m"]).T
    deg = np.degrees
    kind = result.get("plant", {}).get("kind", "surrogate")
    fig = plt.figure(figsize=(13, 9.5), constrained_layout=True)
    grid = fig.add_gridspec(3, 2, width_ratios=[2.2, 1])
    ax_rod = fig.add_subplot(grid[0, 0])
    ax_roll = fig.add_subplot(grid[1, 0], sharex=ax_rod)
    ax_pitch = fig.add_subplot(grid[2, 0], sharex=ax_rod)
    ax_xy = fig.add_subplot(grid[:, 1])
    _rod_heatmap(fig, ax_rod, t, rods, float(result["params"]["l_max"]))
    ax_rod.set_title(
        f"commanded rod lengths ({result['driver']} driver, rate-limited to "
        f"{result['params']['rod_speed_m_s']} m/s)", fontsize=10
    )
    ax_rod.tick_params(labelbottom=False)
    ax_roll.plot(t, deg(s["roll_desired_rad"]), "k--", lw=1.2, label="desired roll")
    ax_roll.plot(t, deg(s["roll_rad"]), "C0", lw=1.5, label=f"roll ({kind} plant)")
    ax_roll.plot(t, deg(s["phi_vpip_rad"]), "C3", lw=1.0, label="φ_VPIP")
    ax_roll.set_ylabel("angle (deg)")
    ax_roll.set_title("roll: desired, reached, and the plane's φ_VPIP", fontsize=10)
    ps.legend_right(ax_roll)
    ax_roll.grid(alpha=0.3)
    ax_roll.tick_params(labelbottom=False)
    ax_pitch.plot(t, deg(s["theta_vpip_rad"]), "C2", lw=1.0, label="θ_VPIP (deg, left axis)")
    ax_w = ax_pitch.twinx()
    ax_w.plot(t, s["omega_desired_rad_s"], "k--", lw=1.2, label="desired ω (rad/s)")
    ax_w.plot(t, s["omega_rad_s"], "C1", lw=1.5, label=f"ω ({kind} plant, rad/s)")
    ax_w.set_ylabel("ω (rad/s)")
    ax_pitch.set_ylabel("θ_VPIP (deg)")
    ax_pitch.set_xlabel("time (s)")
    ax_pitch.set_title("speed: the plane's θ_VPIP and the rolling rate ω", fontsize=10)
    lines = ax_pitch.get_lines() + ax_w.get_lines()
    ps.legend_below(ax_pitch, lines, ncol=3, labels=[str(line.get_label()) for line in lines])
    ax_pitch.grid(alpha=0.3)
    if plan is not None:
        xs = [st["x"] for st in plan["states"]]
        ys = [st["y"] for st in plan["states"]]
        ax_xy.plot(xs, ys, "k--", lw=1.2, label="planned")
    ax_xy.plot(s["x"], s["y"], "C0", lw=1.5, label=f"tracked ({kind} plant)")
    ax_xy.plot(s["x"][0], s["y"][0], "o", color=ps.START_COLOUR, label="start")
    ax_xy.plot(s["x"][-1], s["y"][-1], "*", ms=10, color=ps.GOAL_COLOUR, label="end of the run")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set_xlabel("x (m)")
    ax_xy.set_ylabel("y (m)")
    ps.legend_below(ax_xy, ncol=2)
    ax_xy.grid(alpha=0.3)
    summ = result["summary"]
    reached = "reached the path's end" if summ.get("reached_end", True) else "did NOT reach the path's end"
    ax_xy.set_title(
        f"ground track: {reached}\ncross-track error rms {summ.get('rms_lateral_error_m', float('nan')):.2f} m, "
        f"max {summ['max_lateral_error_m']:.2f} m",
        fontsize=9,
    )
    what = "MuJoCo rod physics" if kind == "mujoco" else "surrogate plant, not rod physics"
    duration = f", {float(t[-1] - t[0]):.1f} s" if len(t) else ""
    fig.suptitle(f"VPIP schedule: {result['robot']} along the planned path — {what}{duration}")
    return fig


def plot_schedule(result: Mapping[str, Any], out: str | Path, plan: Mapping[str, Any] | None = None) -> None:
    """Write a PNG of ``result`` (from :func:`planner.vpip.cascade.run_schedule`) to ``out``.

    Panels: the 16 commanded rod lengths as a heat map (rod number × time in s); desired and simulated roll
    with φ_VPIP; θ_VPIP with desired and simulated ω; the planned and tracked paths (x–y, metres).
    """
    from planner.plotstyle import save

    save(schedule_figure(result, plan), out, dpi=90)


def plot_circle(result: Mapping[str, Any], out: str | Path) -> None:
    """Write a PNG of a circle run (:func:`planner.vpip.circle.run_circle`) to ``out``.

    Panels: the track with the fitted circle; desired and measured roll with φ_VPIP; ω with θ_VPIP;
    the rod lengths (measured on the MuJoCo plant, commanded on the surrogate) as a heat map.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = result["series"]
    summ = result["summary"]
    t = np.asarray(s["t"])
    rods = np.asarray(s.get("rod_measured_m") or s["rod_length_m"]).T
    deg = np.degrees
    fig = plt.figure(figsize=(12, 8), constrained_layout=True)
    grid = fig.add_gridspec(3, 2, width_ratios=[1.0, 1.6])
    ax_xy = fig.add_subplot(grid[:, 0])
    ax_roll = fig.add_subplot(grid[0, 1])
    ax_w = fig.add_subplot(grid[1, 1], sharex=ax_roll)
    ax_rod = fig.add_subplot(grid[2, 1], sharex=ax_roll)
    ax_xy.plot(s["x"], s["y"], "C0", lw=1.3, label="sphere centre")
    ax_xy.plot(s["x"][0], s["y"][0], "ko", ms=4, label="start")
    if summ["diameter_m"] is not None:
        cx, cy = summ["circle_centre_m"]
        a = np.linspace(0, 2 * np.pi, 200)
        r = 0.5 * summ["diameter_m"]
        ax_xy.plot(cx + r * np.cos(a), cy + r * np.sin(a), "k--", lw=0.8, label=f"fit: D = {summ['diameter_m']:.2f} m")
    paper = summ.get("paper_diameter_m")
    if paper is not None and summ["diameter_m"] is not None:
        cx, cy = summ["circle_centre_m"]
        a = np.linspace(0, 2 * np.pi, 200)
        ax_xy.plot(
            cx + 0.5 * paper * np.cos(a), cy + 0.5 * paper * np.sin(a), "C3:", lw=1.0, label=f"paper: D = {paper} m"
        )
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set_xlabel("x (m)")
    ax_xy.set_ylabel("y (m)")
    ax_xy.legend(fontsize=8, loc="best")
    ax_xy.grid(alpha=0.3)
    ax_roll.axhline(summ["roll_desired_deg"], color="k", ls="--", lw=1.0, label="desired roll")
    ax_roll.plot(t, deg(s["roll_rad"]), "C0", lw=1.0, label="roll")
    phi = np.asarray([np.nan if v is None else v for v in s["phi_vpip_rad"]], dtype=float)
    ax_roll.plot(t, deg(phi), "C3", lw=0.6, alpha=0.7, label="φ_VPIP")
    ax_roll.set_ylabel("deg")
    ax_roll.legend(fontsize=8, loc="upper right", ncol=3)
    ax_roll.grid(alpha=0.3)
    if summ.get("omega_desired_rad_s") is not None:
        ax_w.axhline(summ["omega_desired_rad_s"], color="k", ls="--", lw=1.0, label="desired ω")
    ax_w.plot(t, s["omega_rad_s"], "C1", lw=0.8, label="ω (rad/s)")
    theta = np.asarray([np.nan if v is None else v for v in s["theta_vpip_rad"]], dtype=float)
    ax_w.plot(t, theta, "C2", lw=0.8, label="θ_VPIP (rad)")
    ax_w.legend(fontsize=8, loc="upper right", ncol=3)
    ax_w.grid(alpha=0.3)
    _rod_heatmap(fig, ax_rod, t, rods, float(result["params"]["l_max"]))
    ax_rod.set_xlabel("time (s)")
    kind = result["plant"]["kind"]
    d = "—" if summ["diameter_m"] is None else f"{summ['diameter_m']:.2f} m"
    fig.suptitle(
        f"{summ['driver']} driver on the {kind} plant — desired roll {summ['roll_desired_deg']:.1f}°, "
        f"mean roll {summ['mean_roll_deg']:.1f}°, mean ω {summ['mean_omega_rad_s']:.2f} rad/s, diameter {d}"
    )
    fig.savefig(out, dpi=90)
    plt.close(fig)
