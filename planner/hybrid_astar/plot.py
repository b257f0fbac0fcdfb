"""Pictures of plans: the map (free, clearance band, unknown, occupied), the path coloured by roll (forward solid,
reverse dashed), footprints, start and goal; for a failed plan the start and goal footprints, the one in
collision red with the blocked cells it overlaps. Style: :mod:`planner.plotstyle`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from planner import plotstyle as ps
from planner.maps.clearance import CircleFootprint
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile


def endpoint_in_collision(grid: OccupancyGrid, robot: RobotProfile, pose: tuple[float, float, float]) -> bool:
    """Whether the padded footprint at ``pose`` meets a blocked cell or leaves the map (what the picture marks)."""
    world = ps.footprint_world(robot, pose)
    ext = ps.map_extent(grid)
    outside = (world[:, 0].min() < ext[0] or world[:, 0].max() > ext[1] or world[:, 1].min() < ext[2]
               or world[:, 1].max() > ext[3])
    return bool(outside or len(ps.offending_cells(grid, world)))


def plan_figure(
    grid: OccupancyGrid, robot: RobotProfile, states: np.ndarray | None, start: tuple[float, float, float],
    goal: tuple[float, float, float], title: str = "", n_circles: int = 3, footprint_every_m: float = 1.0,
) -> Any:
    """The matplotlib figure of a plan (``states`` (n, 8) as in :mod:`planner.result`, or None for a failed plan:
    then the start and goal footprints are drawn, one in collision red with the cells it overlaps)."""
    plt = ps.pyplot()
    from matplotlib.collections import LineCollection

    fp = CircleFootprint.for_robot(robot, n_circles)
    extent = ps.map_extent(grid)
    pts = [start[:2], goal[:2]]
    if states is not None:
        pts += list(states[:, :2])
    else:  # failed: both footprints whole in view
        pts += list(ps.footprint_world(robot, start)) + list(ps.footprint_world(robot, goal))
    box = ps.view_box(np.array(pts, dtype=float), extent)
    fig, ax = plt.subplots(figsize=ps.figure_size(box), dpi=110)
    handles: list[Any] = ps.draw_map(ax, grid, fp.radius_m)
    if states is not None and len(states) > 1:
        xy = states[:, :2]
        segs = np.stack([xy[:-1], xy[1:]], axis=1)
        reverse = ps.reverse_segments(states[:, 4])
        lim = math.degrees(robot.max_roll_rad)
        lc = LineCollection(list(segs), cmap="coolwarm", linewidths=2.6, zorder=3)
        lc.set_array(np.degrees(states[:-1, 3]))
        lc.set_clim(-lim, lim)
        ax.add_collection(lc)
        ps.reverse_overlay(ax, xy, reverse, lw=1.1)
        fig.colorbar(lc, ax=ax, fraction=0.03, pad=0.02, label="roll (deg, > 0 turns left)")
        from matplotlib.lines import Line2D

        if (~reverse).any():
            handles.append(Line2D([], [], color="0.3", lw=2.6, label="forward (colour: roll)"))
        if reverse.any():
            pair = (Line2D([], [], color="0.3", lw=2.6), Line2D([], [], color="white", lw=1.1, ls=(0, (3, 3))))
            handles.append(_Pair(pair, "reverse (white dashes; colour: roll)"))
        next_s = 0.0
        for row in states:
            if row[6] + 1e-9 >= next_s:
                next_s += footprint_every_m
                ps.draw_footprint(ax, None, robot, row[:3], "darkgreen", "", lw=0.6)
        handles.append(_footprint_handle(f"footprint (padded polygon) every {footprint_every_m:g} m"))
    elif states is None:
        ends = ((start, ps.START_COLOUR, "start footprint"), (goal, ps.GOAL_COLOUR, "goal footprint"))
        for pose, colour, name in ends:
            hit = endpoint_in_collision(grid, robot, pose)
            handles += ps.draw_footprint(ax, grid, robot, pose, colour, name, collided=hit)
    handles.append(ps.draw_pose(ax, start, ps.START_COLOUR, "start"))
    handles.append(ps.draw_pose(ax, goal, ps.GOAL_COLOUR, "goal", marker="*"))
    if ps.view_leaves_map(box, extent):
        handles.append(ps.outside_handle())
    zoom = ps.apply_view(ax, box, extent)
    handles = _dedupe(handles)
    # a _Pair is drawn as its two lines on top of each other (matplotlib's default handler of a tuple)
    ps.legend_below(ax, [h.artists if isinstance(h, _Pair) else h for h in handles], ncol=3,
                    labels=[h.get_label() for h in handles])
    ax.set_title((title or f"{grid.name}: {robot.name}") + zoom, fontsize=10)
    return fig


class _Pair:
    """Two legend artists shown as one entry, with its label."""

    def __init__(self, artists: tuple[Any, Any], label: str) -> None:
        self.artists, self.label = artists, label

    def get_label(self) -> str:
        return self.label


def _footprint_handle(label: str) -> Any:
    from matplotlib.patches import Patch

    return Patch(fill=False, ec="darkgreen", label=label)


def _dedupe(handles: list[Any]) -> list[Any]:
    seen: set[str] = set()
    out = []
    for h in handles:
        if h.get_label() not in seen:
            seen.add(h.get_label())
            out.append(h)
    return out


def plot_plan(
    grid: OccupancyGrid, robot: RobotProfile, states: np.ndarray | None, start: tuple[float, float, float],
    goal: tuple[float, float, float], out: str | Path, title: str = "", n_circles: int = 3,
    footprint_every_m: float = 1.0,
) -> Path:
    """Write a PNG of a plan (``states`` (n, 8) as in :mod:`planner.result`, or None for a failed plan)."""
    return ps.save(plan_figure(grid, robot, states, start, goal, title, n_circles, footprint_every_m), out)
