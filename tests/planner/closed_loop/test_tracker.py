"""The eq. 15 MPC and the fallback tracker in the noise-free closed loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.closed_loop.simulate import SimulationOptions, simulate_plan
from planner.closed_loop.tracker import MPCParams, ReferencePath
from planner.errors import InvalidInput
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.synthetic_paths import arc_plan, s_curve_plan, straight_plan

ROBOT = load_robot("zju-60")
FIELD = OccupancyGrid.from_occupied(np.zeros((160, 200), dtype=bool), 0.05, (-2.0, -3.0, 0.0))


def _end_error(plan: dict, sim: dict) -> tuple[float, float]:
    end, last = plan["states"][-1], sim["trajectory"][-1]
    yaw = math.atan2(math.sin(last["yaw"] - end["yaw"]), math.cos(last["yaw"] - end["yaw"]))
    return math.hypot(last["x"] - end["x"], last["y"] - end["y"]), abs(yaw)


@pytest.mark.parametrize(
    "make", [straight_plan, arc_plan, s_curve_plan], ids=["straight", "min-radius-arc", "s"]
)
def test_mpc_tracks_noise_free_within_centimetres(make) -> None:
    plan = make(ROBOT)
    sim = simulate_plan(FIELD, plan, ROBOT, noise="none")
    m = sim["metrics"]
    assert m["reached_goal"] and not m["collided"]
    assert m["fallback_steps"] == 0
    assert m["cross_track_max_m"] < 0.03
    pos, yaw = _end_error(plan, sim)
    assert pos < 0.02 and yaw < 0.03
    assert m["final_position_error_m"] == pytest.approx(pos, abs=1e-5)  # JSON rounds to 1 µm
    # the commands respect the profile
    cmds = np.array([[c["v"], c["roll"]] for c in sim["commands"]])
    assert np.abs(cmds[:, 0]).max() <= ROBOT.max_speed_m_s + 1e-9
    assert np.abs(cmds[:, 1]).max() <= ROBOT.max_roll_rad + 1e-9


def test_arc_really_is_at_the_minimum_radius() -> None:
    states = arc_plan(ROBOT)["states"]
    assert max(abs(s["roll"]) for s in states) == pytest.approx(ROBOT.max_roll_rad)
    assert ROBOT.min_turning_radius_m == pytest.approx(ROBOT.radius_m / math.tan(math.radians(15)))


def test_forward_then_reverse_path_is_split_at_the_cusp_and_rolled_back() -> None:
    fwd = arc_plan(ROBOT)["states"]
    back = [dict(s) for s in reversed(fwd)]  # same poses, driven backwards
    plan = {"states": fwd + back[1:], "robot": ROBOT.to_json()}
    ref = ReferencePath(plan["states"])
    assert [s.direction for s in ref.segments] == [1, -1]
    sim = simulate_plan(FIELD, plan, ROBOT, noise="none")
    m = sim["metrics"]
    assert m["reached_goal"]
    assert min(c["v"] for c in sim["commands"]) < -0.1  # it did reverse
    assert m["final_position_error_m"] < 0.03 and m["cross_track_max_m"] < 0.05


def test_obstacle_constraint_15f_holds_the_centre_off_an_obstacle_the_path_grazes() -> None:
    occ = np.zeros((160, 200), dtype=bool)
    occ[60:64, 80:84] = True  # a 20 cm block at x in [2.0, 2.2], y in [0.0, 0.2]
    grid = OccupancyGrid.from_occupied(occ, 0.05, (-2.0, -3.0, 0.0))
    plan = straight_plan(ROBOT, 4.0, start=(0.0, -0.3, 0.0))  # centre line 30 cm from the block's edge
    cells = np.array([[2.025 + 0.05 * i, 0.025 + 0.05 * j] for i in range(4) for j in range(4)])
    reach = ROBOT.radius_m + 0.05 / math.sqrt(2) + MPCParams().safety_margin_m

    def closest(sim: dict) -> float:
        xy = np.array([[p["x"], p["y"]] for p in sim["trajectory"]])
        return float(np.min(np.hypot(xy[:, None, 0] - cells[None, :, 0], xy[:, None, 1] - cells[None, :, 1])))

    mpc = simulate_plan(grid, plan, ROBOT, noise="none")
    pursuit = simulate_plan(grid, plan, ROBOT, noise="none", options=SimulationOptions(tracker="pursuit"))
    assert closest(pursuit) < reach - 0.02  # following the path exactly would violate 15f
    assert closest(mpc) > reach - 0.01
    assert mpc["metrics"]["reached_goal"]


def test_solver_failures_fall_back_and_are_counted() -> None:
    plan = s_curve_plan(ROBOT)
    opts = SimulationOptions(mpc=MPCParams(max_iter=1))  # the SQP cannot converge in one iteration
    m = simulate_plan(FIELD, plan, ROBOT, noise="none", options=opts)["metrics"]
    assert m["fallback_steps"] > 0
    assert m["reached_goal"] and m["final_position_error_m"] < 0.1


def test_bad_paths_name_the_field() -> None:
    with pytest.raises(InvalidInput, match=r"path\.states"):
        ReferencePath([{"x": 0, "y": 0, "yaw": 0}])
    with pytest.raises(InvalidInput, match=r"path\.states"):
        ReferencePath([{"x": 0, "y": 0}, {"x": 1, "y": 0}])
