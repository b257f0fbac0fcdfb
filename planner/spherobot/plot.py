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


def plot_reconfiguration(result: dict[str, Any], path: str | Path, grid: OccupancyGrid | None = None) -> Path:
    """Write the two-panel PNG for ``result`` to ``path`` and return the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    R = float(result["radius_m"])
    samples = result["samples"]
    xy = np.array([[s["x"], s["y"]] for s in samples])
    quat = np.array([[s["qw"], s["qx"], s["qy"], s["qz"]] for s in samples])
    t = np.array([s["t"] for s in samples])

    fig = plt.figure(figsize=(13, 6))
    ax = fig.add_subplot(1, 2, 1)
    if grid is not None:
        res = grid.resolution_m
        ox, oy = grid.origin[0], grid.origin[1]
        ax.imshow(
            grid.blocked(),
            origin="lower",
            cmap="Greys",
            vmin=0,
            vmax=1.5,
            extent=(ox, ox + grid.width * res, oy, oy + grid.height * res),
        )
    seen: set[str] = set()
    for seg in result["segments"]:
        s0, s1 = seg["t0_s"], seg["t0_s"] + seg["duration_s"]
        m = (t >= s0 - 1e-12) & (t <= s1 + 1e-12)
        label = None if seg["action"] in seen else _NAMES.get(seg["action"], seg["action"])
        seen.add(seg["action"])
        ax.plot(xy[m, 0], xy[m, 1], "-", color=_COLOURS.get(seg["action"], "k"), lw=2, label=label)
    start, goal = result["start"], result["goal"]
    ax.add_patch(Circle((start["x"], start["y"]), R, fill=False, ls="--", color="tab:red"))
    ax.add_patch(Circle((goal["x"], goal["y"]), R, fill=False, color="tab:purple"))
    ax.plot(start["x"], start["y"], "o", color="tab:red", label="start")
    ax.plot(goal["x"], goal["y"], "*", ms=12, color="tab:purple", label="goal")
    heading = result["final"]["heading_rad"]
    ax.annotate(
        "",
        xy=(goal["x"] + 1.5 * R * math.cos(heading), goal["y"] + 1.5 * R * math.sin(heading)),
        xytext=(goal["x"], goal["y"]),
        arrowprops={"arrowstyle": "->", "color": "tab:purple"},
    )
    if "fixed_point_F" in result:
        fx, fy = result["fixed_point_F"]
        cx, cy = result["circle_center"]
        ax.plot(fx, fy, "x", color="k", label="F (P on top)")
        ax.plot(cx, cy, "+", ms=10, color="tab:orange", label="C' (circle centre)")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize=8)
    title = f"{result['method']} {result['mode']} reconfiguration, {result['length_m']:.2f} m"
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
    ax3.legend(loc="upper left", fontsize=8)
    fig.colorbar(sc, ax=ax3, shrink=0.6, label="t (s)")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
