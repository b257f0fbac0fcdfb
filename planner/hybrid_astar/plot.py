"""Pictures of plans: the map, the inflated obstacles, the path coloured by roll, footprints, start, goal."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from planner.maps.clearance import CircleFootprint, ClearanceMap
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile


def plot_plan(
    grid: OccupancyGrid, robot: RobotProfile, states: np.ndarray | None, start: tuple[float, float, float],
    goal: tuple[float, float, float], out: str | Path, title: str = "", n_circles: int = 3,
    footprint_every_m: float = 1.0,
) -> Path:
    """Write a PNG of a plan (``states`` (n, 8) as in :mod:`planner.result`, or None for a failed plan)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrow, Patch, Polygon

    fp = CircleFootprint.for_robot(robot, n_circles)
    clear = ClearanceMap(grid)
    ox, oy = grid.origin[0], grid.origin[1]
    w, h = grid.size_m
    extent = (ox, ox + w, oy, oy + h)
    # the view: what matters (path, start, goal) with the map around it, never more than the map
    pts = np.array([start[:2], goal[:2], *([] if states is None else states[:, :2])], dtype=float)
    margin = max(3.0, 0.15 * float(np.ptp(pts, axis=0).max()))
    x0, x1 = max(extent[0], pts[:, 0].min() - margin), min(extent[1], pts[:, 0].max() + margin)
    y0, y1 = max(extent[2], pts[:, 1].min() - margin), min(extent[3], pts[:, 1].max() + margin)
    vw, vh = max(x1 - x0, 1e-6), max(y1 - y0, 1e-6)
    fig, ax = plt.subplots(figsize=(10, 10 * vh / vw + 1.6) if vw >= vh else (10 * vw / vh + 1.5, 11.6), dpi=110)
    # one layer, four classes: 0 free, 1 clearance band, 2 unknown, 3 occupied
    layer = np.where(clear.clearance < fp.radius_m, 1, 0)
    layer[grid.data < 0] = 2
    layer[grid.data >= grid.occupied_threshold] = 3
    colours = ["#ffffff", "#b9d6ea", "#a8a8a8", "#111111"]
    ax.imshow(layer, origin="lower", extent=extent, cmap=ListedColormap(colours), vmin=-0.5, vmax=3.5,
              interpolation="nearest")
    handles: list[Any] = [
        Patch(fc=colours[0], ec="0.6", label="free"),
        Patch(fc=colours[1], label=f"clearance band (< {fp.radius_m:.2f} m from a blocked cell)"),
        Patch(fc=colours[2], label="unknown (blocked)"),
        Patch(fc=colours[3], label="occupied"),
    ]
    if states is not None and len(states) > 1:
        xy = states[:, :2]
        segs = np.stack([xy[:-1], xy[1:]], axis=1)
        reverse = states[:-1, 4] < 0
        lim = math.degrees(robot.max_roll_rad)
        lc = None
        for mask, style in ((~reverse, "solid"), (reverse, (0, (2, 1.5)))):
            if not mask.any():
                continue
            lc = LineCollection(list(segs[mask]), cmap="coolwarm", linewidths=2.4, linestyles=style)
            lc.set_array(np.degrees(states[:-1, 3][mask]))
            lc.set_clim(-lim, lim)
            ax.add_collection(lc)
        if lc is not None:
            fig.colorbar(lc, ax=ax, fraction=0.03, pad=0.02, label="roll (deg, > 0 turns left)")
        handles.append(Line2D([], [], color="0.3", lw=2.4, label="forward"))
        if reverse.any():
            handles.append(Line2D([], [], color="0.3", lw=2.4, ls=(0, (2, 1.5)), label="reverse"))
        poly = robot.footprint_polygon
        next_s = 0.0
        for row in states:
            if row[6] + 1e-9 >= next_s:
                next_s += footprint_every_m
                x, y, yaw = row[:3]
                c, sn = math.cos(yaw), math.sin(yaw)
                world = np.column_stack([x + c * poly[:, 0] - sn * poly[:, 1], y + sn * poly[:, 0] + c * poly[:, 1]])
                ax.add_patch(Polygon(world, closed=True, fill=False, lw=0.6, ec="darkgreen", alpha=0.8))
        label = f"footprint (padded polygon) every {footprint_every_m:g} m"
        handles.append(Patch(fill=False, ec="darkgreen", label=label))
    for pose, colour, label in ((start, "green", "start"), (goal, "red", "goal")):
        x, y, yaw = pose
        ax.plot([x], [y], "o", color=colour, ms=7, zorder=5)
        ax.add_patch(FancyArrow(x, y, 0.8 * math.cos(yaw), 0.8 * math.sin(yaw), width=0.06, color=colour, zorder=5))
        handles.append(Line2D([], [], marker="o", color=colour, ls="", label=label))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    # below the axes, never over the data
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=3, fontsize=8, frameon=False)
    zoom = "" if (x0, x1, y0, y1) == extent else f" (view {vw:.0f} × {vh:.0f} m of {w:.0f} × {h:.0f} m)"
    ax.set_title((title or f"{grid.name}: {robot.name}") + zoom)
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out)
    plt.close(fig)
    return out
