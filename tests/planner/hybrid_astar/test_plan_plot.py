"""The plan picture follows the shared style (planner.plotstyle): legend entries, zoom, forward/reverse."""

from __future__ import annotations

import numpy as np

from planner.hybrid_astar.plot import plan_figure
from planner.maps.catalogue import default_maps_dir
from planner.maps.load import load_any
from planner.occupancy import OccupancyGrid
from planner.plotstyle import legend_labels, offending_cells, view_box
from planner.robot import load_robot


def _states(xy: np.ndarray, v: np.ndarray) -> np.ndarray:
    n = len(xy)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    return np.column_stack([xy, np.zeros(n), np.zeros(n), v, np.arange(n) * 0.1, s, np.zeros(n)])


def test_plan_figure_has_every_map_class_forward_reverse_and_a_zoomed_title() -> None:
    robot = load_robot("zju-60")
    grid = load_any(default_maps_dir() / "garage.yaml", robot)
    xy = np.column_stack([np.linspace(10, 14, 30), np.full(30, 8.05)])
    v = np.where(np.arange(30) < 15, 0.5, -0.5)
    fig = plan_figure(grid, robot, _states(xy, v), (10, 8.05, 0), (14, 8.05, 0), title="garage: test")
    labels = legend_labels(fig)
    for entry in ("free", "unknown (blocked)", "occupied", "start", "goal"):
        assert entry in labels
    assert any(label.startswith("clearance band") for label in labels)
    assert "forward (colour: roll)" in labels and "reverse (white dashes; colour: roll)" in labels
    ax = fig.axes[0]
    assert "garage: test" in ax.get_title() and "view" in ax.get_title()  # zoomed into the 40 × 30 m map
    x0, x1 = ax.get_xlim()
    assert 0 < x0 < 10 and 14 < x1 < 40
    # the legend sits below the axes, not over the data
    legend = ax.get_legend()
    fig.canvas.draw()
    assert legend.get_window_extent().y1 <= ax.get_window_extent().y0


def test_offending_cells_and_view_box() -> None:
    occ = np.zeros((20, 20), bool)
    occ[10, 10] = True
    grid = OccupancyGrid.from_occupied(occ, 0.1)
    square = np.array([[0.95, 0.95], [1.2, 0.95], [1.2, 1.2], [0.95, 1.2]])
    assert offending_cells(grid, square).tolist() == [[10, 10]]
    assert offending_cells(grid, square + 0.5).tolist() == []
    # inside the map: cut to it; a point outside stays in view
    assert view_box(np.array([[1.0, 1.0]]), (0, 2, 0, 2), min_margin_m=3) == (0, 2, 0, 2)
    assert view_box(np.array([[1.0, 1.0], [5.0, 1.0]]), (0, 2, 0, 2), min_margin_m=1)[1] == 6.0
