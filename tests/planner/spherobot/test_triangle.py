"""Spherical-triangle planner (paper 004 §3): corrected eq. 5, eq. 6, eq. 9/10, complete reconfiguration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from planner.kinematics import wrap
from planner.spherobot.reconfigure import ReconfigureRequest, plan_reconfiguration
from planner.spherobot.rolling import IDENTITY, GroundSegment, roll_polyline, roll_segments, tilt_from_quat
from planner.spherobot.triangle import (
    MAX_FAMILY_DISTANCE,
    right_isosceles,
    solve_triangles,
    spherical_triangle,
    triangle_segments,
)
from tests.reconfigcheck import FAST, PLANS, angle, check_result

side = st.floats(0.05, math.pi - 0.05)


def _roll_triangle(a: float, b: float, C: float, hand: int, R: float = 1.0):
    tri = spherical_triangle(a, b, C)
    x = y = 0.0
    pts = [(0.0, 0.0)]
    for ln, hd in zip((tri.a, tri.b, tri.c), tri.leg_headings(hand), strict=True):
        seg = GroundSegment(x, y, hd, ln * R)
        x, y = seg.end
        pts.append((x, y))
    # roll_polyline: straight rolls only, independent of the closed forms used by the planner
    q = tuple(roll_polyline(IDENTITY, np.array(pts), R)[-1])
    return tri, (x / R, y / R), q


@FAST
@given(side, side, st.floats(0.05, math.pi - 0.05), st.sampled_from([-1, 1]), st.floats(0.1, 3.0))
def test_corrected_displacement_and_excess_against_rolling(a, b, C, hand, R):
    tri, (dx, dy), q = _roll_triangle(a, b, C, hand, R)
    theta, _, yaw = tilt_from_quat(q)
    assert theta < 1e-9  # the contact point came back: P is on top again
    # eq. 9 / 10: yaw = −E (left-handed) or +E (right-handed)
    assert abs(wrap(yaw - hand * tri.excess)) < 1e-9
    # corrected eq. 5 and eq. 6 (printed for the left-handed path; mirrored for right-handed)
    d2 = (
        tri.a**2
        + tri.b**2
        + tri.c**2
        - 2 * tri.a * tri.b * math.cos(tri.C)
        + 2 * tri.a * tri.c * math.cos(tri.A + tri.C)
        - 2 * tri.b * tri.c * math.cos(tri.A)
    )
    assert math.isclose(math.hypot(dx, dy), math.sqrt(max(d2, 0.0)), abs_tol=1e-9)
    assert np.allclose(tri.displacement(hand), (dx, dy), atol=1e-9)
    phi6 = math.atan2(
        tri.b * math.sin(tri.C) - tri.c * math.sin(tri.A + tri.C),
        tri.a - tri.b * math.cos(tri.C) + tri.c * math.cos(tri.A + tri.C),
    )
    if math.hypot(dx, dy) > 1e-6:
        assert abs(wrap(math.atan2(dy, dx) - (-hand) * phi6)) < 1e-6


def test_printed_eq_5_is_not_the_rolled_displacement():
    tri, (dx, dy), _ = _roll_triangle(0.5, 0.7, 1.0, -1)
    printed = (
        tri.a**2
        + tri.b**2
        + tri.c**2
        - 2 * tri.a * tri.c * math.cos(tri.A + tri.C)
        - 2 * tri.a * tri.b * math.cos(tri.C)
        - 2 * tri.a * tri.b * math.cos(tri.A)
    )
    assert abs(math.sqrt(printed) - math.hypot(dx, dy)) > 0.1


@FAST
@given(st.floats(1e-3, math.pi - 1e-3))
def test_right_isosceles_closed_form_is_the_general_triangle(excess):
    t = right_isosceles(excess)
    g = spherical_triangle(t.a, t.b, t.C)
    assert math.isclose(t.excess, excess, abs_tol=1e-12)
    assert math.isclose(g.excess, excess, abs_tol=1e-9)
    assert np.allclose((t.c, t.A, t.B), (g.c, g.A, g.B), atol=1e-9)


@pytest.mark.parametrize("d", [0.0, 1e-9, 0.01, 0.5, 1.5, 2.5, math.pi, 4.0])
@pytest.mark.parametrize("yaw", [0.0, 1e-9, 0.3, -0.3, 1.6, -2.9, math.pi])
def test_at_most_two_triangles_reach_every_displacement_and_yaw(d, yaw):
    sols = solve_triangles(d * math.cos(0.7), d * math.sin(0.7), yaw)
    assert sols, "no triangle pair found"
    for _, legs in sols[:4]:
        assert 1 <= len(legs) <= 2
        segs = triangle_segments(legs, 0.0, 0.0, 1.0, [], "t")
        q = roll_segments(IDENTITY, segs, 1.0)
        x, y = segs[-1].end
        theta, _, spin = tilt_from_quat(q)
        assert math.hypot(x - d * math.cos(0.7), y - d * math.sin(0.7)) < 1e-9
        assert theta < 1e-9
        assert abs(wrap(spin - yaw)) < 1e-9


def test_sum_of_the_two_excesses_is_the_yaw():
    _, legs = solve_triangles(1.0, 0.5, 2.0)[0]
    assert abs(wrap(sum(leg.triangle.yaw(leg.hand) for leg in legs) - 2.0)) < 1e-12


def _request(complete: bool, R, sx, sy, gx, gy, th, al, spin, head) -> ReconfigureRequest:
    return ReconfigureRequest(
        method="triangle",
        start=(sx * R, sy * R),
        goal=(gx * R, gy * R),
        start_tilt=(th, al),
        start_spin=spin,
        goal_heading=head if complete else None,
        radius_m=R,
        roll_rate_rad_s=1.0,
    )


coord = st.floats(-8.0, 8.0)


@PLANS
@given(st.floats(0.05, 4.0), coord, coord, coord, coord, st.floats(0.0, math.pi), angle, angle, angle)
def test_complete_reconfiguration_meets_the_goal(R, sx, sy, gx, gy, th, al, spin, head):
    req = _request(True, R, sx, sy, gx, gy, th, al, spin, head)
    res = plan_reconfiguration(req)
    check_result(res, req.goal, head)
    assert len(res["triangles"]) <= 2
    assert all(s["kind"] == "line" for s in res["segments"])


@PLANS
@given(st.floats(0.05, 4.0), coord, coord, coord, coord, st.floats(0.0, math.pi), angle, angle)
def test_partial_reconfiguration_meets_the_goal(R, sx, sy, gx, gy, th, al, spin):
    req = _request(False, R, sx, sy, gx, gy, th, al, spin, None)
    res = plan_reconfiguration(req)
    check_result(res, req.goal, None)
    assert len(res["triangles"]) <= 2


def test_start_already_at_the_goal_with_p_on_top_only_turns():
    res = plan_reconfiguration(
        {"method": "triangle", "start": [1.0, 2.0], "goal": [1.0, 2.0], "goal_heading": 1.0, "radius_m": 0.5}
    )
    check_result(res, (1.0, 2.0), 1.0)
    assert res["final"]["heading_error_rad"] < 1e-9


def test_every_displacement_up_to_pi_and_every_yaw_is_reachable():
    """§3.2's claim on the d–α rectangle 0 ≤ d ≤ π, −π ≤ α ≤ π (a dense grid; ≤ 2 triangles each)."""
    for d in np.linspace(0.0, math.pi, 15):
        for yaw in np.linspace(-math.pi, math.pi, 25):
            sols = solve_triangles(d, 0.0, float(yaw))
            assert sols and len(sols[0][1]) <= 2
    assert MAX_FAMILY_DISTANCE > math.pi
