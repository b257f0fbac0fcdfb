"""Pictures of plans: the map, the inflated obstacles, the path coloured by roll, footprints, start, goal."""

from __future__ import annotations

import math
from pathlib import Path

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
    from matplotlib.patches import Circle, FancyArrow, Rectangle

    fp = CircleFootprint.for_robot(robot, n_circles)
    clear = ClearanceMap(grid)
    ox, oy = grid.origin[0], grid.origin[1]
    w, h = grid.size_m
    extent = (ox, ox + w, oy, oy + h)
    fig, ax = plt.subplots(figsize=(10, 10 * h / w + 0.8) if w >= h else (10 * w / h + 1.5, 10), dpi=110)
    inflated = (clear.clearance < fp.radius_m).astype(float)
    ax.imshow(inflated, origin="lower", extent=extent, cmap="Blues", vmin=0, vmax=3, interpolation="nearest")
    blocked = np.ma.masked_where(~grid.blocked(), np.ones(grid.data.shape))
    ax.imshow(blocked, origin="lower", extent=extent, cmap="gray_r", vmin=0, vmax=1, interpolation="nearest")
    if states is not None and len(states) > 1:
        pts = states[:, :2]
        segs = np.stack([pts[:-1], pts[1:]], axis=1)
        lc = LineCollection(list(segs), cmap="coolwarm", linewidths=2.2)
        lim = math.degrees(robot.max_roll_rad)
        lc.set_array(np.degrees(states[:-1, 3]))
        lc.set_clim(-lim, lim)
        ax.add_collection(lc)
        fig.colorbar(lc, ax=ax, fraction=0.03, pad=0.02, label="roll (deg, > 0 turns left)")
        next_s = 0.0
        for row in states:
            if row[6] + 1e-9 >= next_s:
                next_s += footprint_every_m
                x, y, yaw = row[:3]
                rect = Rectangle((-robot.footprint_length_m / 2, -robot.footprint_width_m / 2),
                                 robot.footprint_length_m, robot.footprint_width_m, fill=False, lw=0.6,
                                 ec="darkgreen", alpha=0.7)
                t = matplotlib.transforms.Affine2D().rotate(yaw).translate(x, y) + ax.transData
                rect.set_transform(t)
                ax.add_patch(rect)
                for cx, cy in fp.centres(x, y, yaw):
                    ax.add_patch(Circle((cx, cy), fp.radius_m, fill=False, lw=0.4, ec="orange", alpha=0.6))
    for pose, colour, label in ((start, "green", "start"), (goal, "red", "goal")):
        x, y, yaw = pose
        ax.plot([x], [y], "o", color=colour, ms=7, label=label)
        ax.add_patch(FancyArrow(x, y, 0.8 * math.cos(yaw), 0.8 * math.sin(yaw), width=0.06, color=colour))
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or f"{grid.name}: {robot.name}")
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out)
    plt.close(fig)
    return out
