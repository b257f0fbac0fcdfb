"""Picture of one closed-loop simulation: the map with the planned path and the true, fused and
odometry-only trajectories (paper 001 Fig. 7 style), next to the errors and commands over time.

Style (:mod:`planner.plotstyle`): the four map classes in the legend, forward solid and reverse dashed, the
footprint at the first pose where the true run collided (red, with the cells it overlaps), the view zoomed
to the run with the map around it, legends outside the data."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from planner import plotstyle as ps
from planner.closed_loop.simulate import cross_track_distance
from planner.occupancy import OccupancyGrid


def first_collision(grid: OccupancyGrid, polygon: np.ndarray, poses: np.ndarray) -> int | None:
    """Index of the first pose (rows x, y, yaw) whose padded footprint meets a blocked cell or the map's edge."""
    from planner.maps.clearance import ClearanceMap

    dist = ClearanceMap(grid).footprint_distances(polygon, poses, reach_m=0.1)
    hit = np.flatnonzero(dist <= 0.0)
    return int(hit[0]) if len(hit) else None


def simulation_figure(grid: OccupancyGrid, plan_json: dict[str, Any], sim: dict[str, Any]) -> Any:
    """The figure :func:`plot_simulation` writes."""
    from matplotlib.lines import Line2D

    from planner.maps.clearance import CircleFootprint

    plt = ps.pyplot()
    states = plan_json["states"]
    path = np.array([[s["x"], s["y"]] for s in states])
    path_rev = ps.reverse_segments(np.array([s.get("v", 1.0) for s in states]))
    tr = np.array([[r["t"], r["x"], r["y"], r.get("yaw", 0.0), r.get("v", 1.0)] for r in sim["trajectory"]])
    es = np.array([[r["x"], r["y"]] for r in sim["estimate"]])
    od = np.array([[r["x"], r["y"]] for r in sim["odometry"]])
    gn = np.array([[r["x"], r["y"]] for r in sim["gnss"]]).reshape(-1, 2)
    cmd = np.array([[r["t"], r["v"], r["roll"]] for r in sim["commands"]]).reshape(-1, 3)
    m = sim["metrics"]
    polygon = np.asarray(sim["robot"]["footprint"], float)
    true_rev = ps.reverse_segments(tr[:, 4])

    fig = plt.figure(figsize=(14, 8), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=(1.5, 1))
    ax = fig.add_subplot(gs[:, 0])
    extent = ps.map_extent(grid)
    box = ps.view_box(np.vstack([path, tr[:, 1:3], od, es]), extent, min_margin_m=2.0, frac=0.1)
    handles: list[Any] = ps.draw_map(ax, grid, CircleFootprint.covering(polygon, 3).radius_m)
    if len(gn):
        ax.plot(gn[:, 0], gn[:, 1], ".", color="0.55", ms=2, zorder=2)
        handles.append(Line2D([], [], marker=".", color="0.55", ls="", label="GNSS fixes"))
    handles += ps.path_line(ax, path, path_rev, "black", lw=1.4, label="planned path")
    ax.plot(od[:, 0], od[:, 1], ":", color="tab:red", lw=1.3, zorder=3)
    handles.append(Line2D([], [], ls=":", color="tab:red", lw=1.3, label="wheel odometry only (eq. 2)"))
    handles += ps.path_line(ax, es, true_rev[: len(es)], "tab:green", lw=1.2, label="fused estimate (eq. 3)")
    handles += ps.path_line(ax, tr[:, 1:3], true_rev, "tab:blue", lw=1.0, label="true trajectory")
    handles.append(ps.draw_pose(ax, (path[0, 0], path[0, 1], states[0].get("yaw", 0.0)), ps.START_COLOUR, "start",
                                arrow_m=0.5))
    handles.append(ps.draw_pose(ax, (path[-1, 0], path[-1, 1], states[-1].get("yaw", 0.0)), ps.GOAL_COLOUR,
                                "goal (path's end)", arrow_m=0.5, marker="*"))
    hit = first_collision(grid, polygon, tr[:, 1:4]) if m.get("collided") else None
    if hit is not None:
        handles += ps.draw_footprint(ax, grid, polygon, tr[hit, 1:4], "red",
                                     f"true footprint at the first collision, t = {tr[hit, 0]:.1f} s", collided=True)
    if ps.view_leaves_map(box, extent):
        handles.append(ps.outside_handle())
    zoom = ps.apply_view(ax, box, extent)
    ps.legend_below(ax, handles, ncol=3)
    ax.set_title(
        f"{grid.name}: {sim['robot']['name']} in closed loop · {sim['tracker']} tracker · noise {sim['noise']} · "
        f"seed {sim['seed']}{zoom}\n"
        f"cross-track rms {m['cross_track_rms_m'] * 100:.1f} cm, max {m['cross_track_max_m'] * 100:.1f} cm · "
        f"final error {m['final_position_error_m'] * 100:.1f} cm · clearance {m['min_clearance_m']:.2f} m"
        + (" · COLLIDED" if m["collided"] else ""),
        fontsize=9,
    )

    ae = fig.add_subplot(gs[0, 1])
    ae.plot(tr[:, 0], cross_track_distance(path, tr[:, 1:3]) * 100, color="tab:blue", label="cross-track (true)")
    ae.plot(tr[:, 0], np.hypot(*(es - tr[:, 1:3]).T) * 100, color="tab:green", label="fused estimate error")
    ae.plot(tr[:, 0], np.hypot(*(od - tr[:, 1:3]).T) * 100, ":", color="tab:red", label="odometry error")
    if hit is not None:
        ae.axvline(tr[hit, 0], color="red", lw=0.8, label="first collision")
    ae.set_ylabel("error (cm, symlog)")
    ae.set_yscale("symlog", linthresh=1.0)
    ae.set_title("errors over time", fontsize=9)
    ae.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.12), ncol=2, frameon=False)
    ae.grid(alpha=0.3)

    ac = fig.add_subplot(gs[1, 1], sharex=ae)
    ac.plot(cmd[:, 0], cmd[:, 1], color="tab:purple", label="v command (m/s)")
    ac.axhline(0.0, color="0.5", lw=0.6)
    ac.set_ylabel("v (m/s, < 0 reverse)")
    ac.set_xlabel("t (s)")
    ar = ac.twinx()
    ar.plot(cmd[:, 0], np.degrees(cmd[:, 2]), color="tab:orange", lw=0.8, label="roll command (°)")
    ar.set_ylabel("roll (°)")
    ac.set_title("commands", fontsize=9)
    lines = ac.get_lines()[:1] + ar.get_lines()
    ac.legend(lines, [str(line.get_label()) for line in lines], fontsize=8, loc="upper left",
              bbox_to_anchor=(0.0, -0.15), ncol=2, frameon=False)
    ac.grid(alpha=0.3)
    return fig


def plot_simulation(
    grid: OccupancyGrid, plan_json: dict[str, Any], sim: dict[str, Any], out: str | Path
) -> None:
    """Write a PNG of ``sim`` (a :func:`~planner.closed_loop.simulate.simulate_plan` result) over ``grid``."""
    ps.save(simulation_figure(grid, plan_json, sim), out)
