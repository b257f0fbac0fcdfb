"""The reconfiguration picture (issue #13): on a map, zoomed to the manoeuvre with the map around it."""

from __future__ import annotations

import math

from planner.maps.catalogue import default_maps_dir
from planner.maps.nav2 import load_map
from planner.plotstyle import legend_labels
from planner.spherobot.plot import reconfiguration_figure
from planner.spherobot.reconfigure import plan_reconfiguration
from planner.spherobot.request import ReconfigureRequest


def test_garage_manoeuvre_is_zoomed_with_the_map_around_it() -> None:
    grid = load_map(default_maps_dir() / "garage.yaml")
    request = ReconfigureRequest.from_dict({
        "method": "arc", "radius_m": 0.3, "start": [12.0, 8.05], "start_tilt": [math.radians(30), math.radians(75)],
        "goal": [14.0, 8.05]})
    fig = reconfiguration_figure(plan_reconfiguration(request, grid=grid), grid)
    ax = fig.axes[0]
    assert "on garage" in ax.get_title() and "view" in ax.get_title()
    x0, x1 = ax.get_xlim()
    assert x1 - x0 < 15.0 and x0 < 12.0 - 2.0 and x1 > 14.0 + 2.0  # a few metres of map around, not all 40 m
    labels = legend_labels(fig)
    assert {"free", "occupied", "unknown (blocked)"} <= set(labels)
    assert any(label.startswith("clearance band") for label in labels)
