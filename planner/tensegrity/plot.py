"""Pictures of TeXploR's gaits: paper 002 Fig. 9's contact-angle maps with the planned slider path.

Four maps over the slider plane (θ1, θ2) ∈ [0°, 180°]², one per state, colour = the rolling link's
contact angle where the state is at rest (blank where it is not), the transition boundaries c_y = 0
dotted red, and the planned path's legs in that state drawn over it; a fifth panel shows the ground
track (centre O_b and both contacts) of the gait.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from planner.tensegrity.geometry import TexplorParams, centre_of_mass
from planner.tensegrity.statics import STATES, closed_form_angle


def contact_angle_map(state: int, params: TexplorParams, n: int = 121) -> tuple[np.ndarray, np.ndarray]:
    """(grid (deg, shape (n,)), contact angle (deg, shape (n, n), [θ2, θ1]), NaN where off the arc)."""
    grid = np.linspace(0.0, math.pi, n)
    out = np.full((n, n), np.nan)
    for j, t2 in enumerate(grid):
        for i, t1 in enumerate(grid):
            phi = closed_form_angle(state, t1, t2, params)
            if 0.0 <= phi <= math.pi:
                out[j, i] = math.degrees(phi)
    return np.degrees(grid), out


def gait_figure(result: dict[str, Any], params: TexplorParams) -> Any:
    """The figure :func:`plot_gait` writes (style: :mod:`planner.plotstyle`)."""
    from matplotlib.lines import Line2D

    from planner import plotstyle as ps

    plt = ps.pyplot()
    steps = result["steps"]
    fig, axes = plt.subplots(2, 3, figsize=(16, 10), layout="constrained")
    fine = np.linspace(0.0, math.pi, 241)
    cy = np.array([[centre_of_mass(t1, t2, params)[1] for t1 in fine] for t2 in fine])
    image = None
    th1 = np.degrees([s["theta1_rad"] for s in steps])
    th2 = np.degrees([s["theta2_rad"] for s in steps])
    for state, ax in zip((1, 2, 3, 4), (axes[0, 0], axes[0, 1], axes[1, 0], axes[1, 1]), strict=True):
        grid_deg, angles = contact_angle_map(state, params)
        image = ax.pcolormesh(grid_deg, grid_deg, angles, vmin=0, vmax=180, cmap="viridis", shading="auto")
        ax.contour(
            np.degrees(fine), np.degrees(fine), cy, levels=[0.0], colors="red", linestyles=":", linewidths=2
        )
        rolling = STATES[state].rolling_link
        ax.plot(th1, th2, color="white", lw=1, alpha=0.6)
        mine = np.array([s["state"] == state for s in steps])
        ax.plot(np.where(mine, th1, np.nan), np.where(mine, th2, np.nan), color="magenta", lw=3)
        ax.plot(th1[0], th2[0], "wo", ms=8, mec="k")
        ax.plot(th1[-1], th2[-1], "w*", ms=14, mec="k")
        ax.set_title(f"state {state} (pivot {STATES[state].pivot_name}): contact angle φ{rolling}", fontsize=10)
        ax.set_xlabel("θ1 (deg)")
        ax.set_ylabel("θ2 (deg)")
        ax.set_aspect("equal")
        ax.set_xlim(0, 180)
        ax.set_ylim(0, 180)
    if image is not None:
        fig.colorbar(image, ax=axes[:, :2].ravel().tolist(), shrink=0.8,
                     label="contact angle of the rolling link (deg); blank: the state is not at rest")
    map_handles = [
        Line2D([], [], color="magenta", lw=3, label="slider path while in this state"),
        Line2D([], [], color="white", lw=1.5, label="rest of the slider path", mec="k",
               path_effects=_outline()),
        Line2D([], [], color="red", ls=":", lw=2, label="transition boundary c_y = 0"),
        Line2D([], [], marker="o", color="white", mec="k", ls="", ms=8, label="start"),
        Line2D([], [], marker="*", color="white", mec="k", ls="", ms=12, label="end"),
    ]
    ps.legend_below(axes[1, 0], map_handles, ncol=3)
    ax = axes[0, 2]
    centre = np.array([s["centre_m"] for s in steps])
    q1 = np.array([s["q1_ground_m"] for s in steps])
    q2 = np.array([s["q2_ground_m"] for s in steps])
    ax.plot(centre[:, 0], centre[:, 1], "k-", lw=2, label="centre O_b")
    ax.plot(q1[:, 0], q1[:, 1], ".", color="tab:blue", ms=3, label="contact Q1 (link 1)")
    ax.plot(q2[:, 0], q2[:, 1], ".", color="tab:orange", ms=3, label="contact Q2 (link 2)")
    ax.plot(centre[0, 0], centre[0, 1], "o", color=ps.START_COLOUR, label="start")
    ax.plot(centre[-1, 0], centre[-1, 1], "*", ms=12, color=ps.GOAL_COLOUR, label="end")
    ax.annotate("", xy=(0.95, 0.06), xytext=(0.75, 0.06), xycoords="axes fraction",
                arrowprops={"arrowstyle": "->", "color": "0.3"})
    ax.text(0.85, 0.08, "+x", transform=ax.transAxes, ha="center", va="bottom", fontsize=8, color="0.3")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    dx = centre[-1, 0] - centre[0, 0]
    ax.set_title(
        f"ground track: {result['direction']} {abs(result['distance_m']):.3g} m ({result['measure']}),\n"
        f"O_b moved {dx:+.3f} m along x", fontsize=10
    )
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ps.legend_below(ax, ncol=2)
    ax = axes[1, 2]
    t = [s["t"] for s in steps]
    ax.plot(t, th1, label="θ1 (deg)")
    ax.plot(t, th2, label="θ2 (deg)")
    ax.plot(t, [30 * s["state"] for s in steps], "k--", lw=1, label="state × 30")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("slider angle (deg)")
    ax.set_title("slider trajectories θ1(t), θ2(t)", fontsize=10)
    ax.grid(alpha=0.3)
    ps.legend_below(ax, ncol=3)
    fig.suptitle(
        f"TeXploR gait ({result['robot']}): roll {result['distance_m']:+.3g} m along x, states "
        f"{'→'.join(map(str, result['state_sequence']))}, {result['duration_s']:.1f} s "
        "(paper 002 Fig. 9 maps over the slider plane)"
    )
    return fig


def _outline() -> list[Any]:
    from matplotlib import patheffects

    return [patheffects.withStroke(linewidth=3, foreground="0.4")]


def plot_gait(result: dict[str, Any], params: TexplorParams, path: str | Path) -> None:
    """Write the Fig. 9-style figure of a :func:`plan_gait` result to ``path`` (PNG)."""
    from planner.plotstyle import save

    save(gait_figure(result, params), path, dpi=90)
