"""Curvature cascade: roll model round trips, the paper's three runs, whole schedules."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import InvalidInput
from planner.robot import load_robot
from planner.synthetic_paths import circle_plan, plan_from_curvatures, straight_plan
from planner.vpip.api import calibrate_report, radius_report, roll_report
from planner.vpip.cascade import PathReference, run_schedule

DAEDALUS = load_robot("daedalus")


def test_default_table_reproduces_the_papers_three_runs() -> None:
    for roll_deg, diameter in ((5, 2.6), (10, 2.0), (15, 1.7)):
        out = radius_report(math.radians(roll_deg), DAEDALUS)
        assert 2 * out["radius_m"] == pytest.approx(diameter, rel=1e-9)


@pytest.mark.parametrize("radius", [0.9, 1.0, 1.2, 1.7, 3.0, 10.0])
def test_radius_roll_radius_round_trip(radius: float) -> None:
    for left in (True, False):
        roll = roll_report(radius, DAEDALUS, left=left)["roll_rad"]
        assert (roll > 0) == left
        assert radius_report(roll, DAEDALUS)["radius_m"] == pytest.approx(radius, rel=1e-5)


def test_beyond_the_table_is_held_and_flagged() -> None:
    out = roll_report(0.5, DAEDALUS)
    assert not out["achievable"] and out["achieved_radius_m"] == pytest.approx(0.85)
    assert radius_report(math.radians(25), DAEDALUS)["beyond_table"]


def test_calibrate_refits_the_paper_runs() -> None:
    csv = "roll_deg,diameter_m\n5,2.5\n5,2.7\n10,2.0\n15,1.7\n"
    out = calibrate_report(csv, DAEDALUS)
    assert out["roll_model"]["roll_deg"] == pytest.approx([5, 10, 15])
    # two runs at 5 deg are averaged in curvature
    assert out["roll_model"]["diameter_m"][0] == pytest.approx(2 / (0.5 * (1 / 1.25 + 1 / 1.35)))
    with pytest.raises(InvalidInput, match="runs"):
        calibrate_report("roll_deg,diameter_m\n5,1.0\n10,2.0\n", DAEDALUS)  # radius grows with roll


@pytest.mark.parametrize(
    "plan",
    [
        straight_plan(DAEDALUS, 1.5),
        circle_plan(DAEDALUS, 1.2, 0.35),
        plan_from_curvatures(DAEDALUS, [(0.5, 0.0), (math.pi / 2, 1.0), (math.pi / 2, -1.0), (0.5, 0.0)]),  # S-curve
    ],
    ids=["straight", "circle", "s-curve"],
)
@pytest.mark.parametrize("driver", ["vpip", "simple"])
def test_schedule_never_moves_a_rod_faster_than_rod_speed(plan: dict, driver: str) -> None:
    out = run_schedule(plan, DAEDALUS, driver=driver, max_duration_s=12.0)
    s = out["series"]
    rods = np.asarray(s["rod_length_m"])
    dt = 1.0 / out["rate_hz"]
    assert rods.shape == (len(s["t"]), 16)
    assert np.max(np.abs(np.diff(rods, axis=0))) <= out["params"]["rod_speed_m_s"] * dt + 1e-12
    assert np.all((rods >= 0) & (rods <= out["params"]["l_max"]))
    assert np.max(np.abs(s["phi_vpip_rad"])) <= math.radians(20) + 1e-12
    assert np.max(np.abs(s["theta_vpip_rad"])) <= math.radians(40) + 1e-12


def test_vpip_tracks_circle_with_surrogate_plant() -> None:
    plan = circle_plan(DAEDALUS, 1.2, 0.5)
    out = run_schedule(plan, DAEDALUS)
    summ = out["summary"]
    assert summ["reached_end"]
    assert summ["max_lateral_error_m"] < 0.1
    # the held roll is the roll model's roll for R = 1.2 m
    want = DAEDALUS.roll_model.roll_for_curvature(1 / 1.2)
    s = out["series"]
    late = np.asarray(s["t"]) > 8.0
    assert np.mean(np.asarray(s["roll_rad"])[late]) == pytest.approx(want, abs=math.radians(1.5))


def test_bad_plans_name_the_field() -> None:
    with pytest.raises(InvalidInput, match=r"path\.states"):
        PathReference.from_plan({"states": []}, DAEDALUS)
    plan = straight_plan(DAEDALUS, 0.5)
    plan["states"][3]["x"] = "a"
    with pytest.raises(InvalidInput, match=r"states\[3\].x"):
        PathReference.from_plan(plan, DAEDALUS)
    rev = plan_from_curvatures(DAEDALUS, [(0.5, 0.0)])
    rev["states"][2]["v"] = -0.1
    with pytest.raises(InvalidInput, match="v"):
        PathReference.from_plan(rev, DAEDALUS)
    with pytest.raises(InvalidInput, match="driver"):
        run_schedule(straight_plan(DAEDALUS, 0.5), DAEDALUS, driver="magic")
    with pytest.raises(InvalidInput, match="robot"):
        run_schedule(straight_plan(DAEDALUS, 0.5), load_robot("zju-60"))
