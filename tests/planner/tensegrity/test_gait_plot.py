"""The gait picture (issue #13): legends outside the maps, titles saying what and which way it rolled."""

from __future__ import annotations

from planner.plotstyle import legend_labels
from planner.robot import load_robot
from planner.tensegrity import plan_gait
from planner.tensegrity.geometry import params_from_profile
from planner.tensegrity.plot import gait_figure


def test_gait_figure_says_what_and_where() -> None:
    profile = load_robot("texplor")
    fig = gait_figure(plan_gait(0.5, profile, steps=6), params_from_profile(profile))
    labels = legend_labels(fig)
    assert {"transition boundary c_y = 0", "slider path while in this state", "centre O_b", "start", "end"} <= set(
        labels)
    assert "+0.5 m along x" in fig._suptitle.get_text()
    track = fig.axes[2]
    assert "O_b moved +0.500 m along x" in track.get_title()
    fig.canvas.draw()
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is not None:  # below its axes, not over the data
            assert legend.get_window_extent().y1 <= ax.get_window_extent().y0
