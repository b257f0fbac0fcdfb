"""Plan → tracker (eq. 15 / pursuit) → LMPC + RSLQR → dynamic plant, and the GNSS-denied patrol (Fig. 10).

The full sweep over every shipped solvable problem is ``lab/pendulum/rollout.py`` (minutes; its last
run is reported in docs/pendulum.md); these are the quick checks CI runs.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from planner.closed_loop.patrol import patrol, turn_overshoots
from planner.closed_loop.simulate import SimulationOptions, simulate_plan
from planner.errors import InvalidInput
from planner.maps.nav2 import save_map
from planner.occupancy import OccupancyGrid
from planner.pendulum.sphere import DynamicSphere
from planner.robot import load_robot
from planner.synthetic_paths import s_curve_plan
from service.cli import main

ROBOT = load_robot("zju-60")
FIELD = OccupancyGrid.from_occupied(np.zeros((160, 240), dtype=bool), 0.05, (-2.0, -4.0, 0.0))


def test_dynamic_model_follows_an_s_curve_and_reports_the_pendulum() -> None:
    plan = s_curve_plan(ROBOT)
    opts = SimulationOptions(tracker="pursuit", model="dynamic")
    sim = simulate_plan(FIELD, plan, ROBOT, seed=0, noise="none", options=opts)
    m = sim["metrics"]
    assert sim["model"] == "dynamic"
    assert m["reached_goal"] and not m["collided"]
    assert m["final_position_error_m"] < 0.15 and m["cross_track_max_m"] < 0.15
    assert 0.05 < m["pendulum_pitch_max_rad"] < math.radians(16)
    assert m["pendulum_roll_max_rad"] > 0.02 and m["lmpc_solve_ms_p50"] > 0
    # the roll now has dynamics of its own: it is not the kinematic simulator's first-order lag
    kin = simulate_plan(FIELD, plan, ROBOT, seed=0, noise="none", options=SimulationOptions(tracker="pursuit"))
    rolls_dyn = np.array([r["roll"] for r in sim["trajectory"]])
    rolls_kin = np.array([r["roll"] for r in kin["trajectory"]])
    n = min(len(rolls_dyn), len(rolls_kin))
    assert np.abs(rolls_dyn[:n] - rolls_kin[:n]).max() > 0.01
    assert kin["metrics"]["pendulum_pitch_max_rad"] is None


def test_dynamic_sphere_moves_like_eq1_from_its_own_speed_and_roll() -> None:
    """The pose integrated by the plant is eq. 1 of the plant's own v and φ (checked by re-integration)."""
    sphere = DynamicSphere(ROBOT, 0.02)
    sphere.reset(1.0, 2.0, 0.5)
    poses = [sphere.snapshot]
    for k in range(150):
        step = sphere.step(None, 0.5, 0.1 if k > 30 else 0.0, 0.02)
        poses.append(step.state)
        assert abs(step.tau_pitch) <= sphere.params.max_torque_pitch_n_m
    x, y, yaw = 1.0, 2.0, 0.5
    for a, b in itertools.pairwise(poses):
        v, roll = 0.5 * (a.v + b.v), 0.5 * (a.roll + b.roll)
        x += 0.02 * (v * math.cos(yaw) - ROBOT.radius_m * (b.roll - a.roll) / 0.02 * math.sin(yaw))
        y += 0.02 * (v * math.sin(yaw) + ROBOT.radius_m * (b.roll - a.roll) / 0.02 * math.cos(yaw))
        yaw += 0.02 * v * math.tan(roll) / ROBOT.radius_m
    end = poses[-1]
    assert math.hypot(end.x - x, end.y - y) < 0.02 and abs(end.yaw - yaw) < 0.01
    assert end.yaw > 0.5 + 0.1  # it turned left


def test_dynamic_sphere_needs_a_dynamics_table() -> None:
    with pytest.raises(InvalidInput, match="dynamics"):
        simulate_plan(FIELD, s_curve_plan(ROBOT), "daedalus", options=SimulationOptions(model="dynamic"))
    with pytest.raises(InvalidInput, match="model"):
        simulate_plan(FIELD, s_curve_plan(ROBOT), ROBOT, options=SimulationOptions(model="rigid"))


def test_patrol_without_gnss_reports_true_and_estimated_error_separately() -> None:
    goals = [(0.0, 0.0, 0.0), (5.0, 0.0, 0.0), (7.0, 2.5, math.pi / 2)]
    res = patrol(FIELD, ROBOT, goals, model="dynamic", seed=1, noise="default",
                 options=SimulationOptions(tracker="pursuit"))
    assert res["gnss"] == [] and res["estimate"] == res["odometry"]  # GNSS-denied: the estimate is odometry
    rep = res["patrol"]
    assert rep["gnss"] == "denied" and len(rep["reached"]) == 2
    tr = {round(r["t"], 4): (r["x"], r["y"]) for r in res["trajectory"]}
    es = {round(r["t"], 4): (r["x"], r["y"]) for r in res["estimate"]}
    for r in rep["reached"]:
        t = round(r["t"], 4)
        gx, gy = r["goal"][:2]
        assert r["true_error_m"] == pytest.approx(math.dist(tr[t], (gx, gy)), abs=1e-6)
        assert r["estimate_error_m"] == pytest.approx(math.dist(tr[t], es[t]), abs=1e-6)
        assert r["believed_distance_m"] < 0.2
    m = res["metrics"]
    # it stops where its odometry puts the last goal; whether that is the goal is judged from the truth
    assert m["stopped_at_estimated_goal"] and not m["collided"]
    assert m["reached_goal"] == (m["final_position_error_m"] <= SimulationOptions().arrival_tolerance_m)
    assert rep["estimate_error_final_m"] > 0.0  # odometry drifts with slip and IMU bias


def test_simulate_cli_model_dynamic(tmp_path: Path) -> None:
    map_yaml = str(save_map(FIELD, tmp_path / "field.yaml"))
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(s_curve_plan(ROBOT)))
    out = tmp_path / "sim.json"
    code = main(["simulate", "--map", map_yaml, "--path", str(plan), "--model", "dynamic", "--tracker", "pursuit",
                 "--noise", "none", "--out", str(out)])
    assert code == 0
    sim = json.loads(out.read_text())
    assert sim["model"] == "dynamic" and sim["metrics"]["pendulum_pitch_max_rad"] > 0
    assert main(["simulate", "--map", map_yaml, "--path", str(plan), "--model", "rigid"]) == 2


def test_turn_overshoot_measures_the_swing_past_zero() -> None:
    t = np.arange(0.0, 10.0, 0.02)
    roll = np.where(t < 3.0, -0.25, 0.0)
    after = (t >= 3.0) & (t < 5.0)
    roll[after] = 0.1 * np.sin(math.pi * (t[after] - 3.0))  # swings to +0.1 past zero, then back
    turns = turn_overshoots(t, roll)
    assert len(turns) == 1
    assert turns[0]["turn_roll_rad"] == pytest.approx(-0.25)
    assert turns[0]["overshoot_rad"] == pytest.approx(0.1, abs=1e-3)
    assert turn_overshoots(t, np.where(t < 0.5, 0.25, 0.0)) == []  # too short to be a turn
