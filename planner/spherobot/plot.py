"""Picture of a reconfiguration result: the ground path (over the map, if any) and P's track on the sphere.

Takes the result dict of ``planner.spherobot.reconfigure.plan_reconfiguration`` and writes a PNG with two panels:
left, the centre's path on the ground coloured by control action (a: straight roll along P's azimuth,
b: circle of radius R·tan θ, roll: spherical-triangle leg) with the sphere's outline at start and goal;
right, P's direction in the world frame (relative to the centre) drawn on the unit sphere, from its start
tilt to the top.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from planner.occupancy import OccupancyGrid

_COLOURS = {"a": "tab:blue", "b": "tab:orange", "roll": "tab:green", "straight": "tab:gray"}
_NAMES = {
    "a": "action (a): roll along P's azimuth",
    "b": "action (b): circle R tan θ",
    "roll": "triangle leg",
    "straight": "straight roll to the goal",
}


def _p_world(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q.T
    return np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def reconfiguration_figure(result: dict[str, Any], grid: OccupancyGrid | None = None) -> Any:
    """The figure :func:`plot_reconfiguration` writes (style: :mod:`planner.plotstyle`): with a map, the view
    is zoomed to the manoeuvre (the sphere's outline included) with the map around it."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch

    from planner import plotstyle as ps

    plt = ps.pyplot()
    R = float(result["radius_m"])
    samples = result["samples"]
    xy = np.array([[s["x"], s["y"]] for s in samples])
    quat = np.array([[s["qw"], s["qx"], s["qy"], s["qz"]] for s in samples])
    t = np.array([s["t"] for s in samples])

    fig = plt.figure(figsize=(14, 7.5), layout="constrained")
    ax = fig.add_subplot(1, 2, 1)
    handles: list[Any] = []
    extent = None
    if grid is not None:
        extent = ps.map_extent(grid)
        handles += ps.draw_map(ax, grid, R)
        handles[1].set_label(f"clearance band (< R = {R:g} m from a blocked cell: the sphere's centre may not be here)")
    seen: set[str] = set()
    for seg in result["segments"]:
        s0, s1 = seg["t0_s"], seg["t0_s"] + seg["duration_s"]
        m = (t >= s0 - 1e-12) & (t <= s1 + 1e-12)
        ax.plot(xy[m, 0], xy[m, 1], "-", color=_COLOURS.get(seg["action"], "k"), lw=2, zorder=3)
        if seg["action"] not in seen:
            seen.add(seg["action"])
            handles.append(Line2D([], [], color=_COLOURS.get(seg["action"], "k"), lw=2,
                                  label=_NAMES.get(seg["action"], seg["action"])))
    start, goal = result["start"], result["goal"]
    ax.add_patch(Circle((start["x"], start["y"]), R, fill=False, ls="--", color="tab:red", zorder=4))
    ax.add_patch(Circle((goal["x"], goal["y"]), R, fill=False, color="tab:purple", zorder=4))
    ax.plot(start["x"], start["y"], "o", color="tab:red", zorder=5)
    ax.plot(goal["x"], goal["y"], "*", ms=12, color="tab:purple", zorder=5)
    handles += [Line2D([], [], marker="o", color="tab:red", ls="--", label="start (sphere outline dashed)"),
                Line2D([], [], marker="*", ms=10, color="tab:purple", label="goal (sphere outline), final heading →")]
    heading = result["final"]["heading_rad"]
    ax.annotate(
        "",
        xy=(goal["x"] + 1.5 * R * math.cos(heading), goal["y"] + 1.5 * R * math.sin(heading)),
        xytext=(goal["x"], goal["y"]),
        arrowprops={"arrowstyle": "->", "color": "tab:purple"},
        zorder=5,
    )
    if "fixed_point_F" in result:
        fx, fy = result["fixed_point_F"]
        cx, cy = result["circle_center"]
        ax.plot(fx, fy, "x", color="k", zorder=5)
        ax.plot(cx, cy, "+", ms=10, color="tab:orange", zorder=5)
        handles += [Line2D([], [], marker="x", color="k", ls="", label="F (P on top)"),
                    Line2D([], [], marker="+", ms=10, color="tab:orange", ls="", label="C' (circle centre)")]
    pts = np.vstack([xy, [[start["x"] + dx, start["y"] + dy] for dx in (-R, R) for dy in (-R, R)],
                     [[goal["x"] + dx, goal["y"] + dy] for dx in (-R, R) for dy in (-R, R)]])
    # with a map: a few metres of it around the manoeuvre (walls in sight); on open ground: a little room
    box = ps.view_box(pts, extent, min_margin_m=max(3.0, 2 * R) if grid is not None else max(1.0, R), frac=0.1)
    if extent is not None and ps.view_leaves_map(box, extent):
        handles.append(ps.outside_handle())
    zoom = ps.apply_view(ax, box, extent)
    if extent is None:
        handles.append(Patch(fc="white", ec="0.6", label="open ground (no --map)"))
    ps.legend_below(ax, handles, ncol=2)
    where = f"on {grid.name}" if grid is not None else "on open ground"
    title = (f"{result['method']} {result['mode']} reconfiguration {where}: {result['length_m']:.2f} m, "
             f"R = {R:g} m{zoom}")
    if "theta_prime_rad" in result:
        title += (
            f"\nθ' = {math.degrees(result['theta_prime_rad']):.1f}°, "
            f"α' = {math.degrees(result['alpha_prime_rad']):.1f}°, {result['circle']} circle"
        )
    ax.set_title(title, fontsize=10)

    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 37), np.linspace(0, np.pi, 19))
    ax3.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", lw=0.5)
    p = _p_world(quat)
    sc = ax3.scatter(p[:, 0], p[:, 1], p[:, 2], c=t, cmap="viridis", s=2, depthshade=False)
    ax3.scatter(*p[0], color="tab:red", edgecolor="k", s=90, depthshade=False, label="P at start")
    ax3.scatter(
        *p[-1], color="tab:purple", edgecolor="k", marker="*", s=160, depthshade=False, label="P at the end"
    )
    ax3.set_box_aspect((1, 1, 1))
    ax3.set_xlabel("x")
    ax3.set_ylabel("y")
    ax3.set_zlabel("z (up)")
    ax3.set_title("P's track on the sphere (world directions from the centre)", fontsize=10)
    ps.legend_below(ax3, ncol=2)
    fig.colorbar(sc, ax=ax3, shrink=0.6, label="time (s)")
    return fig


def plot_reconfiguration(result: dict[str, Any], path: str | Path, grid: OccupancyGrid | None = None) -> Path:
    """Write the two-panel PNG for ``result`` to ``path`` and return the path."""
    from planner.plotstyle import save

    return save(reconfiguration_figure(result, grid), path, dpi=110)
