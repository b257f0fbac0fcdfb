"""Picture of one exploration run: the live map filling in, and every path over time.

One panel per kept moment of the run (the start, replans between, the end): the map as the planner knew it
then (free, unknown, occupied; obstacles of the true world that the given map lacked and the sensor had found
by then in red), every path planned up to then (older ones fainter, the current one bold) and the sphere's true
track so far. Style from :mod:`planner.plotstyle`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from planner import plotstyle as ps
from planner.occupancy import OccupancyGrid


def explore_figure(known: OccupancyGrid, world: OccupancyGrid, result: dict[str, Any]) -> Any:
    """The figure :func:`plot_explore` writes (``result`` as :func:`planner.closed_loop.explore.explore` returns
    it, with its ``_snapshots``)."""
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    plt = ps.pyplot()
    snaps: list[tuple[float, np.ndarray]] = result.get("_snapshots") or [(0.0, known.data)]
    n = len(snaps)
    cols = min(3, n)
    rows = math.ceil(n / cols)
    traj = np.array([[r["t"], r["x"], r["y"]] for r in result["trajectory"]]).reshape(-1, 3)
    xs = np.concatenate([traj[:, 1], [result["start"]["x"], result["goal"]["x"]]])
    ys = np.concatenate([traj[:, 2], [result["start"]["y"], result["goal"]["y"]]])
    for p in result["paths"]:
        xy = np.asarray(p["xy"], float).reshape(-1, 2)
        xs, ys = np.concatenate([xs, xy[:, 0]]), np.concatenate([ys, xy[:, 1]])
    box = ps.view_box(np.column_stack([xs, ys]), ps.map_extent(known))
    w_in = 5.0 * cols
    aspect = (box[3] - box[2]) / max(box[1] - box[0], 1e-9)
    fig, axes = plt.subplots(rows, cols, figsize=(w_in, max(3.0, rows * 5.0 * aspect + 0.8)), squeeze=False)
    hidden = (world.data >= world.occupied_threshold) & (known.data < known.occupied_threshold)
    cmap = ListedColormap(["#ffffff", "#b0b0b0", "#202020", "#d62728"])
    m = result["metrics"]
    for k, (t, data) in enumerate(snaps):
        ax = axes[k // cols][k % cols]
        layer = np.zeros(data.shape, dtype=np.int8)
        layer[data < 0] = 1
        occ = data >= known.occupied_threshold
        layer[occ] = 2
        layer[occ & hidden] = 3
        ax.imshow(layer, origin="lower", extent=ps.map_extent(known), cmap=cmap, vmin=-0.5, vmax=3.5,
                  interpolation="nearest", zorder=0)
        shown = [p for p in result["paths"] if p["t"] <= t + 1e-6]
        for j, p in enumerate(shown):
            xy = np.asarray(p["xy"], float).reshape(-1, 2)
            last = j == len(shown) - 1
            ax.plot(xy[:, 0], xy[:, 1], color="tab:blue", lw=1.6 if last else 0.8, alpha=1.0 if last else 0.35,
                    zorder=3)
        done = traj[traj[:, 0] <= t + 1e-6]
        if len(done):
            ax.plot(done[:, 1], done[:, 2], color="tab:green", lw=1.4, zorder=4)
            ax.plot(done[-1, 1], done[-1, 2], "o", color="tab:green", ms=4, zorder=5)
        ax.plot(result["goal"]["x"], result["goal"]["y"], "*", color="tab:orange", ms=10, zorder=5)
        ax.set_xlim(box[0], box[1])
        ax.set_ylim(box[2], box[3])
        ax.set_aspect("equal")
        ax.set_title(f"t = {t:.1f} s: {len(shown)} path(s)", fontsize=9)
        ax.tick_params(labelsize=7)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    handles = [Patch(fc="#ffffff", ec="0.6", label="free"), Patch(fc="#b0b0b0", label="unknown"),
               Patch(fc="#202020", label="occupied (known)"), Patch(fc="#d62728", label="hidden obstacle, found"),
               Line2D([], [], color="tab:blue", label="paths (current bold)"),
               Line2D([], [], color="tab:green", label="driven (true)")]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=8, frameon=False)
    lat = m["replan_latency_p95_s"]
    fig.suptitle(f"explore: {result['outcome']}, {m['replans']} replans"
                 + (f" (p95 {1e3 * lat:.0f} ms)" if lat is not None else "")
                 + f", driven {m['length_m']:.1f} m"
                 + (f" vs {m['length_known_world_m']:.1f} m with full knowledge" if m["length_known_world_m"] else ""),
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    return fig


def plot_explore(known: OccupancyGrid, world: OccupancyGrid, result: dict[str, Any], out: str | Path) -> Path:
    """Write the exploration figure to ``out``."""
    return ps.save(explore_figure(known, world, result), out)
