"""Arc planner (paper 004 §4): the paper's example, eq. 14, eq. 20 against rolling, goal properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from planner.errors import InvalidInput
from planner.kinematics import wrap
from planner.spherobot.arc import (
    arc_candidates,
    arc_segments,
    offset_of,
    paper_circle_center,
    solve_complete,
    solve_partial_alpha,
    theta_for_offset,
)
from planner.spherobot.reconfigure import ReconfigureRequest, plan_reconfiguration
from planner.spherobot.rolling import GroundSegment, quat_from_tilt, quat_z, roll_polyline, tilt_from_quat
from tests.reconfigcheck import FAST, PLANS, angle, check_result, segments_from_json

coord = st.floats(-8.0, 8.0)

EXAMPLE = {
    "method": "arc",
    "radius_m": 1.0,
    "start": [4.33, 2.50],
    "start_tilt": [30.0, 75.0],
    "goal": [0.0, 0.0],
    "alpha_final": 180.0,
    "degrees": True,
}


def test_paper_example_numbers_and_simulated_end():
    res = plan_reconfiguration(EXAMPLE)
    assert round(math.degrees(res["theta_prime_rad"]), 1) == 75.6
    assert round(math.degrees(res["alpha_prime_rad"]), 1) == 50.9
    assert res["circle"] == "direct"
    assert math.isclose(abs(res["alpha_final_rad"]), math.pi, abs_tol=1e-12)
    assert [s["action"] for s in res["segments"]] == ["a", "a", "b", "a"]
    check_result(res, (0.0, 0.0), None)
    assert res["final"]["position_error_m"] < 1e-9 and res["final"]["p_from_top_rad"] < 1e-9


@pytest.mark.parametrize("R", [0.25, 1.0, 3.0])
def test_paper_example_scales_with_the_radius(R):
    req = dict(EXAMPLE, radius_m=R, start=[4.33 * R, 2.50 * R])
    res = plan_reconfiguration(req)
    assert round(math.degrees(res["theta_prime_rad"]), 1) == 75.6
    assert math.isclose(res["circle_radius_m"], R * math.tan(res["theta_prime_rad"]))
    check_result(res, (0.0, 0.0), None)


def test_eq_14_centre_is_the_geometric_centre():
    th0, al0 = math.radians(30), math.radians(75)
    a, b = paper_circle_center(4.33, 2.50, th0, al0, math.pi)
    fx, fy = 4.33 - th0 * math.cos(al0), 2.50 - th0 * math.sin(al0)
    sol = solve_partial_alpha(fx, fy, math.pi)[0]
    assert math.isclose(math.hypot(a, b), offset_of(sol.theta_prime), rel_tol=1e-12)  # eq. 15
    assert math.isclose(math.hypot(a, b), math.hypot(fx - a, fy - b), rel_tol=1e-12)  # OC' = FC'
    assert math.isclose(math.atan2(fy - b, fx - a), sol.alpha_prime, abs_tol=1e-12)  # eq. 16


@FAST
@given(st.floats(0.0, 50.0))
def test_theta_for_offset_inverts_eq_15(c):
    assert math.isclose(offset_of(theta_for_offset(c)), c, rel_tol=1e-9, abs_tol=1e-12)


@FAST
@given(
    angle,
    st.floats(0.05, 1.5),
    st.floats(-6.2, 6.2).filter(lambda v: abs(v) > 1e-3),
    angle,
    st.floats(0.1, 3),
)
def test_eq_20_heading_change_against_rolling(alpha_p, theta_p, delta_alpha, psi0, R):
    """Steps 2–4 from P on top: the heading changes by Δα(1 − 1/cos θ'), and P ends on top."""
    from planner.spherobot.arc import ArcSolution

    sol = ArcSolution(theta_p, alpha_p, delta_alpha, "direct")
    segs = arc_segments(sol, 0.0, 0.0, R)
    pts = [np.array([[0.0, 0.0]])]
    for seg in segs:
        s = np.linspace(0, seg.length_m, 2001 if seg.kind == "arc" else 2)[1:]
        pts.append(np.column_stack(seg.point_at(s)))
    q = tuple(roll_polyline(quat_z(psi0), np.concatenate(pts), R)[-1])
    theta, _, heading = tilt_from_quat(q)
    assert theta < 1e-4
    assert abs(wrap(heading - psi0 - sol.delta_q)) < 1e-3
    # eq. 21: the chord F→O of the circle about C'
    end = segs[-1].end
    assert math.isclose(
        math.hypot(*end) / R,
        2 * offset_of(theta_p) * abs(math.sin(delta_alpha / 2)),
        rel_tol=1e-9,
        abs_tol=1e-12,
    )


def _request(complete, R, sx, sy, gx, gy, th, al, spin, head, alpha_final=None) -> ReconfigureRequest:
    return ReconfigureRequest(
        method="arc",
        start=(sx * R, sy * R),
        goal=(gx * R, gy * R),
        start_tilt=(th, al),
        start_spin=spin,
        goal_heading=head if complete else None,
        alpha_final=alpha_final,
        radius_m=R,
        roll_rate_rad_s=1.0,
    )


@PLANS
@given(st.floats(0.05, 4.0), coord, coord, coord, coord, st.floats(0.0, math.pi), angle, angle, angle)
def test_complete_reconfiguration_meets_the_goal(R, sx, sy, gx, gy, th, al, spin, head):
    req = _request(True, R, sx, sy, gx, gy, th, al, spin, head)
    res = plan_reconfiguration(req)
    check_result(res, req.goal, head)
    actions = [s["action"] for s in res["segments"]]
    assert actions[-3:] == ["a", "b", "a"] and set(actions) <= {"a", "b"}
    assert 0 < res["theta_prime_rad"] < math.pi / 2


@PLANS
@given(st.floats(0.05, 4.0), coord, coord, coord, coord, st.floats(0.0, math.pi), angle, angle)
def test_partial_reconfiguration_meets_the_goal(R, sx, sy, gx, gy, th, al, spin):
    req = _request(False, R, sx, sy, gx, gy, th, al, spin, None)
    res = plan_reconfiguration(req)
    check_result(res, req.goal, None)


@PLANS
@given(st.floats(0.05, 4.0), coord, coord, st.floats(0.0, math.pi), angle, angle, angle)
def test_partial_with_alpha_final_ends_rolling_along_alpha_final(R, sx, sy, th, al, spin, alpha_f):
    fx, fy = sx - th * math.cos(al), sy - th * math.sin(al)  # F after step 1 backwards (unit sphere)
    feasible = fx * math.cos(alpha_f) + fy * math.sin(alpha_f) < -1e-6 * max(1.0, math.hypot(fx, fy))
    try:
        res = plan_reconfiguration(_request(False, R, sx, sy, 0, 0, th, al, spin, None, alpha_f))
    except InvalidInput as exc:
        assert not feasible and exc.field == "alpha_final"
        return
    check_result(res, (0.0, 0.0), None)
    if res["circle"] is None:  # F already at the goal: step 1 alone, no final roll to orient
        assert res["theta_prime_rad"] is None and len(res["segments"]) <= 1
        return
    assert abs(wrap(res["alpha_final_rad"] - alpha_f)) < 1e-9
    last = res["segments"][-1]
    assert abs(wrap(last["heading_rad"] - alpha_f - math.pi)) < 1e-9


def test_direct_and_complementary_circles_are_both_offered():
    cands = arc_candidates(
        (4.33, 2.5), quat_from_tilt(math.radians(30), math.radians(75)), (0, 0), None, math.pi, 1.0
    )
    circles = {(m.info["circle"], m.info["turn"]) for m in cands}
    assert ("direct", "counter-clockwise") in circles and ("complementary", "clockwise") in circles
    direct = next(m for m in cands if m.info["circle"] == "direct")
    comp = next(m for m in cands if m.info["circle"] == "complementary")
    assert math.isclose(comp.info["delta_alpha_rad"], direct.info["delta_alpha_rad"] - 2 * math.pi)  # eq. 23


def test_complete_solutions_cover_every_branch_kind():
    sols = solve_complete(3.0, 1.0, 0.4)
    assert sols and all(abs(wrap(s.delta_q - 0.4)) < 1e-9 for s in sols)
    assert sols == sorted(sols, key=lambda s: s.length)


@pytest.mark.parametrize("heading", [0.0, 0.5, -2.0, math.pi])
def test_f_on_the_goal_still_reaches_any_heading(heading):
    """r = 0: no circle can turn the heading, so step 1 adds a full revolution (orientation unchanged)."""
    th, al = 0.4, 1.1
    start = (th * math.cos(al), th * math.sin(al))  # F = origin
    req = ReconfigureRequest("arc", start, (0.0, 0.0), (th, al), 0.3, heading, None, 1.0, 1.0)
    res = plan_reconfiguration(req)
    check_result(res, (0.0, 0.0), heading)


def test_segments_round_trip_through_json():
    res = plan_reconfiguration(EXAMPLE)
    segs = segments_from_json(res)
    for seg, js in zip(segs, res["segments"], strict=True):
        assert np.allclose(seg.end, js["end"])
        assert isinstance(seg, GroundSegment)
        if js["action"] == "b":
            assert math.isclose(js["omega_yp_rad_s"], 0.0, abs_tol=1e-12)  # action (b): ω'y = 0
        if js["action"] == "a" and js["step"].startswith("step 2"):
            assert math.isclose(js["omega_xp_rad_s"], 0.0, abs_tol=1e-9)  # action (a): ω'x = 0
