"""Synthetic reference paths: plan-format, dense, rollable, and the track spans 16.2 m × 8.4 m and closes."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from planner.closed_loop.localization import OdometryIncrement, odometry_step
from planner.errors import InvalidInput
from planner.robot import load_robot
from planner.synthetic_paths import (
    arc_plan,
    circle_plan,
    plan_from_curvatures,
    plan_from_rolls,
    s_curve_plan,
    straight_plan,
    track_plan,
)

ROBOT = load_robot("zju-60")


@pytest.mark.parametrize(
    "plan",
    [straight_plan(ROBOT), arc_plan(ROBOT), s_curve_plan(ROBOT), track_plan(ROBOT)],
    ids=["straight", "arc", "s", "track"],
)
def test_plan_format_and_spacing(plan: dict) -> None:
    states = plan["states"]
    assert set(states[0]) == {"x", "y", "yaw", "roll", "v", "t", "s", "curvature"}
    xy = np.array([[s["x"], s["y"]] for s in states])
    assert np.hypot(*np.diff(xy, axis=0).T).max() <= 0.05
    assert max(abs(s["roll"]) for s in states) <= ROBOT.max_roll_rad + 1e-12
    assert plan["robot"]["name"] == "zju-60"


def test_track_spans_the_rectangle_and_closes() -> None:
    plan = track_plan(ROBOT, origin=(1.0, 2.0))
    xy = np.array([[s["x"], s["y"]] for s in plan["states"]])
    np.testing.assert_allclose(xy.min(axis=0), [1.0, 2.0], atol=0.02)
    np.testing.assert_allclose(xy.max(axis=0), [17.2, 10.4], atol=0.02)
    assert np.hypot(*(xy[-1] - xy[0])) < 0.01
    assert plan["states"][-1]["yaw"] - plan["states"][0]["yaw"] == pytest.approx(-2 * math.pi, abs=1e-3)
    # clockwise: the signed area is negative
    assert 0.5 * np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1]) < 0
    with pytest.raises(InvalidInput, match="corner_radius_m"):
        track_plan(ROBOT, corner_radius_m=0.5)


def test_consecutive_states_obey_eq1() -> None:
    """Each step of a path is eq. 1's recursion (the odometry step) over its arc length and roll change."""
    plan = plan_from_rolls(ROBOT, [(1.0, 0.0), (1.5, 0.2), (1.0, -0.1)], speed_m_s=0.4)
    states = plan["states"]
    worst = 0.0
    for a, b in itertools.pairwise(states):
        pose, _ = odometry_step(
            np.array([a["x"], a["y"], a["yaw"]]),
            OdometryIncrement(b["s"] - a["s"], a["roll"], b["roll"]),
            ROBOT,
        )
        worst = max(worst, math.hypot(pose[0] - b["x"], pose[1] - b["y"]), abs(pose[2] - b["yaw"]))
    assert worst < 5e-4  # a wrong roll-shift sign or factor would give millimetres


def test_curvature_plans_are_exact_arcs() -> None:
    robot = load_robot("daedalus")
    plan = plan_from_curvatures(robot, [(0.5, 0.0), (2 * math.pi * 1.2, 1 / 1.2)], spacing_m=0.02)
    st = plan["states"]
    xy = np.array([[s["x"], s["y"]] for s in st])
    assert np.hypot(*np.diff(xy, axis=0).T).max() <= 0.02 + 1e-12
    # the full circle after the run-in ends where it began, heading +x again (one turn later)
    assert math.hypot(st[-1]["x"] - 0.5, st[-1]["y"]) < 1e-9
    assert st[-1]["yaw"] == pytest.approx(2 * math.pi)
    # every circle state lies 1.2 m from the centre (0.5, 1.2), with the roll of that curvature
    circle = [s for s in st if s["s"] > 0.5 + 1e-9]
    assert all(abs(math.hypot(s["x"] - 0.5, s["y"] - 1.2) - 1.2) < 1e-9 for s in circle)
    assert all(s["roll"] == pytest.approx(float(robot.roll_model.roll_for_curvature(1 / 1.2))) for s in circle)
    assert circle_plan(robot, 1.2, 1.0)["length_m"] == pytest.approx(0.5 + 2 * math.pi * 1.2)
