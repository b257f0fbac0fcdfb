"""The simulation picture follows the shared style: map classes, forward/reverse, the collided footprint."""

from __future__ import annotations

import math

import numpy as np

from planner.closed_loop.plot import first_collision, simulation_figure
from planner.occupancy import OccupancyGrid
from planner.plotstyle import legend_labels
from planner.robot import load_robot


def _sim(xs: np.ndarray, y: float, v: float, collided: bool) -> dict:
    robot = load_robot("zju-60")
    rows = [{"t": 0.1 * i, "x": float(x), "y": y, "yaw": 0.0, "roll": 0.0, "v": v} for i, x in enumerate(xs)]
    return {
        "robot": robot.to_json(), "tracker": "mpc", "noise": "none", "seed": 0,
        "trajectory": rows, "estimate": rows, "odometry": rows, "gnss": [],
        "commands": [{"t": r["t"], "v": v, "roll": 0.0} for r in rows],
        "metrics": {"cross_track_rms_m": 0.0, "cross_track_max_m": 0.0, "final_position_error_m": 0.0,
                    "min_clearance_m": 0.0 if collided else 0.5, "collided": collided},
    }


def _grid() -> OccupancyGrid:
    occ = np.zeros((100, 200), bool)  # 10 m × 5 m at 5 cm
    occ[:, 120:124] = True  # a wall at x = 6.0–6.2 m
    return OccupancyGrid.from_occupied(occ, 0.05, name="wall")


def test_collided_run_shows_the_footprint_at_the_first_collision() -> None:
    grid = _grid()
    xs = np.linspace(1.0, 7.0, 61)
    sim = _sim(xs, 2.5, 0.5, collided=True)
    plan = {"states": [{"x": float(x), "y": 2.5, "yaw": 0.0, "v": 0.5} for x in xs]}
    polygon = np.asarray(sim["robot"]["footprint"], float)
    poses = np.column_stack([xs, np.full_like(xs, 2.5), np.zeros_like(xs)])
    hit = first_collision(grid, polygon, poses)
    assert hit is not None and 5.0 < xs[hit] < 6.0  # the footprint's front reaches the wall before its centre
    labels = legend_labels(simulation_figure(grid, plan, sim))
    for entry in ("free", "occupied", "unknown (blocked)", "planned path", "true trajectory"):
        assert entry in labels
    assert any(label.startswith("true footprint at the first collision") and label.endswith("(in collision)")
               for label in labels)
    assert any(label.startswith("blocked cells it overlaps") for label in labels)


def test_reverse_run_is_drawn_dashed_and_zoomed() -> None:
    grid = _grid()
    xs = np.linspace(4.0, 1.0, 31)
    sim = _sim(xs, 2.5, -0.5, collided=False)
    plan = {"states": [{"x": float(x), "y": 2.5, "yaw": 0.0, "v": -0.5 if i else 0.0} for i, x in enumerate(xs)]}
    fig = simulation_figure(grid, plan, sim)
    labels = legend_labels(fig)
    assert "planned path (reverse)" in labels and "true trajectory (reverse)" in labels
    assert "planned path (forward)" not in labels and not any("collision" in label for label in labels)
    ax = fig.axes[0]
    assert ax.get_title().startswith("wall: zju-60 in closed loop")
    dashed = [line for line in ax.get_lines() if line.get_linestyle() not in ("-", "None", ":")]
    assert dashed  # reverse runs are dashed lines
    assert not math.isclose(ax.get_xlim()[1], 10.0)  # zoomed: not the whole 10 m map
