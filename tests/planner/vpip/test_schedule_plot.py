"""The schedule picture (issue #13): rod numbers on the heat map's axis, time in seconds, a title."""

from __future__ import annotations

from planner.plotstyle import legend_labels
from planner.robot import load_robot
from planner.synthetic_paths import straight_plan
from planner.vpip import api
from planner.vpip.plot import schedule_figure


def test_schedule_figure_labels_rods_time_and_title() -> None:
    plan = straight_plan(load_robot("daedalus"), 1.0)
    result = api.schedule_report(plan, "daedalus", "vpip", "surrogate")
    fig = schedule_figure(result, plan)
    ax_rod, ax_roll, ax_pitch = fig.axes[0], fig.axes[1], fig.axes[2]
    assert [t.get_text() for t in ax_rod.get_yticklabels()] == [str(k) for k in range(16)]
    assert ax_rod.get_ylabel() == "rod number"
    assert ax_pitch.get_xlabel() == "time (s)"
    assert fig._suptitle.get_text().startswith("VPIP schedule: daedalus")
    labels = legend_labels(fig)
    assert {"desired roll", "planned", "start", "end of the run"} <= set(labels)
    fig.canvas.draw()
    legend = ax_roll.get_legend()  # beside the roll panel, not over its data
    assert legend.get_window_extent().x0 >= ax_roll.get_window_extent().x1
