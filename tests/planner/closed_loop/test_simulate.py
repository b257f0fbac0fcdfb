"""The closed loop: determinism, the paper's positioning run, footprint clearance, the benchmark rows."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planner.closed_loop.simulate import SimulationOptions, simulate_plan
from planner.closed_loop.simulator import Disturbances
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.synthetic_paths import s_curve_plan, track_plan
from tests.contracts import SIM_METRIC_KEYS

ROBOT = load_robot("zju-60")
FIELD = OccupancyGrid.from_occupied(np.zeros((248, 404), dtype=bool), 0.05, (-2.0, -2.0, 0.0))
PURSUIT = SimulationOptions(tracker="pursuit")


def test_same_seed_same_run_other_seed_other_run() -> None:
    plan = s_curve_plan(ROBOT)
    a = simulate_plan(FIELD, plan, ROBOT, seed=7, noise="default")
    b = simulate_plan(FIELD, plan, ROBOT, seed=7, noise="default")
    c = simulate_plan(FIELD, plan, ROBOT, seed=8, noise="default")
    assert a["trajectory"] == b["trajectory"] and a["estimate"] == b["estimate"]
    assert a["trajectory"] != c["trajectory"]
    assert set(a["metrics"]) >= SIM_METRIC_KEYS
    assert set(a["trajectory"][0]) == {"t", "x", "y", "yaw", "roll", "v"}
    assert set(a["commands"][0]) == {"t", "v", "roll"}


def test_track_loop_odometry_drifts_the_fused_estimate_does_not() -> None:
    """Paper 001 §6 / Fig. 7: one clockwise lap of the 16.2 m × 8.4 m track."""
    plan = track_plan(ROBOT)
    m = simulate_plan(FIELD, plan, ROBOT, seed=1, noise="default", options=PURSUIT)["metrics"]
    assert m["reached_goal"] and not m["collided"]
    assert m["odometry_error_final_m"] > 0.3  # accumulated yaw error rotates the odometry lap
    assert m["estimate_error_max_m"] < 0.2
    assert m["estimate_error_rms_m"] < m["odometry_error_rms_m"] / 5


def test_gnss_denied_the_estimate_is_the_odometry() -> None:
    plan = s_curve_plan(ROBOT)
    denied = Disturbances(**{**Disturbances.default().__dict__, "gnss_available": False})
    sim = simulate_plan(FIELD, plan, ROBOT, seed=2, noise=denied, options=PURSUIT)
    assert sim["gnss"] == []
    assert sim["estimate"] == sim["odometry"]


def test_reached_goal_is_decided_by_the_true_position_not_the_estimate() -> None:
    """The robot stops where its estimate says the goal is; reached_goal also needs the truth there."""
    from planner.synthetic_paths import straight_plan

    plan = straight_plan(ROBOT, 2.0, (5.0, 5.0, 0.0))
    normal = simulate_plan(FIELD, plan, ROBOT, seed=3, noise="default", options=PURSUIT)["metrics"]
    assert normal["stopped_at_estimated_goal"] and normal["reached_goal"]
    assert normal["final_position_error_m"] <= PURSUIT.arrival_tolerance_m
    strict = replace(PURSUIT, arrival_tolerance_m=normal["final_position_error_m"] / 2)
    m = simulate_plan(FIELD, plan, ROBOT, seed=3, noise="default", options=strict)["metrics"]
    assert m["stopped_at_estimated_goal"] and not m["reached_goal"]
