"""The picture of one stereo perception (``sphereplan perceive --plot``): what SGBM saw and what was kept.

Left panel: the left image with the disparity map over it (colour = disparity, px; unmatched pixels show the
image) and the kept obstacle pixels outlined. Right panel: top view of the map frame: the sphere's pose, the
10 m range, the sensor origin and the kept points coloured by height.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from planner.perception.stereo import ObstacleScan
from planner.plotstyle import draw_pose, legend_below, pyplot, save


def plot_scan(scan: ObstacleScan, left_image: np.ndarray, pose: tuple[float, float, float], max_range_m: float,
              path: str | Path) -> Path:
    """Draw ``scan`` (its disparity when kept) over ``left_image`` and the kept points from above into ``path``."""
    from matplotlib.lines import Line2D

    plt = pyplot()
    fig, (ax_img, ax_top) = plt.subplots(1, 2, figsize=(13, 5.2), gridspec_kw={"width_ratios": [1.3, 1], "wspace": 0.3})
    grey = left_image if left_image.ndim == 2 else left_image[:, :, ::-1].mean(axis=2)
    ax_img.imshow(grey, cmap="gray", vmin=0, vmax=255)
    if scan.disparity is not None:
        im = ax_img.imshow(np.ma.masked_invalid(scan.disparity), cmap="viridis", alpha=0.55)
        fig.colorbar(im, ax=ax_img, fraction=0.035, pad=0.02, label="disparity (px)")
    if len(scan.pixels):
        ax_img.plot(scan.pixels[:, 1], scan.pixels[:, 0], ",", color="red", alpha=0.6)
    ax_img.set_title(f"left image, SGBM disparity ({scan.num_disparities} levels), kept pixels in red", fontsize=9)
    ax_img.set_axis_off()

    x, y, yaw = pose
    handles = [draw_pose(ax_top, pose, "green", "sphere (pose)", arrow_m=0.8)]
    a = np.linspace(-math.pi, math.pi, 181)
    ax_top.plot(x + max_range_m * np.cos(a), y + max_range_m * np.sin(a), ":", color="grey", lw=1)
    handles.append(Line2D([], [], ls=":", color="grey", label=f"range {max_range_m:g} m"))
    ax_top.plot([scan.origin_map[0]], [scan.origin_map[1]], "^", color="black", ms=6)
    handles.append(Line2D([], [], marker="^", ls="", color="black", label="sensor origin (left camera)"))
    if len(scan.points_map):
        sc = ax_top.scatter(scan.points_map[:, 0], scan.points_map[:, 1], c=scan.points_map[:, 2], s=2,
                            cmap="plasma", vmin=0.0, vmax=max(0.1, float(scan.points_map[:, 2].max())))
        fig.colorbar(sc, ax=ax_top, fraction=0.04, pad=0.02, label="height above ground (m)")
    ax_top.set_aspect("equal")
    ax_top.set_xlim(x - max_range_m - 0.5, x + max_range_m + 0.5)
    ax_top.set_ylim(y - max_range_m - 0.5, y + max_range_m + 0.5)
    ax_top.set_xlabel("x (m, map)")
    ax_top.set_ylabel("y (m, map)")
    ax_top.set_title(f"{len(scan.points_map)} obstacle points kept of {scan.measured} measured", fontsize=9)
    legend_below(ax_top, handles, ncol=3)
    return save(fig, path)
