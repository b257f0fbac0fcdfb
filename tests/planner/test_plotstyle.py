"""The shared plot style's helpers (planner/plotstyle.py)."""

from __future__ import annotations

import numpy as np

from planner import plotstyle as ps
from planner.occupancy import OccupancyGrid


def test_reverse_segments_and_runs() -> None:
    # stops (v = 0) take the next move's sign; the last ones the previous
    assert ps.reverse_segments(np.array([0.0, -0.5, -0.5, 0.0, 0.5, 0.5, 0.0])).tolist() == [
        True, True, True, False, False, False]
    assert ps.runs(np.array([True, True, False, True])) == [(0, 2, True), (2, 3, False), (3, 4, True)]


def test_draw_map_has_a_legend_entry_per_class_and_view_outside_the_map_is_marked() -> None:
    occ = np.zeros((20, 20), bool)
    occ[5:8, 5:8] = True
    data = np.where(occ, 100, 0).astype(np.int8)
    data[15:, 15:] = -1
    grid = OccupancyGrid(data=data, resolution_m=0.1, name="t")
    fig, ax = ps.pyplot().subplots()
    handles = ps.draw_map(ax, grid, 0.2)
    assert [h.get_label() for h in handles] == [
        "free", "clearance band (< 0.20 m from a blocked cell)", "unknown (blocked)", "occupied"]
    box = ps.view_box(np.array([[1.0, 1.0], [3.0, 1.0]]), ps.map_extent(grid), min_margin_m=0.5)
    assert ps.view_leaves_map(box, ps.map_extent(grid))
    assert "beyond the" in ps.apply_view(ax, box, ps.map_extent(grid))
    inside = ps.view_box(np.array([[0.5, 0.5], [1.0, 1.0]]), ps.map_extent(grid), min_margin_m=0.2)
    assert "view" in ps.apply_view(ax, inside, ps.map_extent(grid))
