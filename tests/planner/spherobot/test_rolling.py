"""SO(3) rolling simulator: closed forms against independent integration, and paper 004 eq. 1–4."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.kinematics import wrap
from planner.spherobot.rolling import (
    IDENTITY,
    GroundSegment,
    SpherobotState,
    heading_of,
    model_controls,
    p_world,
    quat_angle,
    quat_axis_angle,
    quat_from_tilt,
    quat_mul,
    quat_normalize,
    quat_rotate,
    quat_to_matrix,
    quat_z,
    roll_polyline,
    roll_segment,
    sample_segment,
    spherobot_rates,
    tilt_from_quat,
)
from tests.reconfigcheck import FAST, angle

SLOW = settings(max_examples=15, derandomize=True, deadline=None)
theta = st.floats(0.0, math.pi)
radius = st.floats(0.05, 5.0)


@FAST
@given(theta, angle, angle)
def test_tilt_puts_p_where_the_paper_says_and_round_trips(th, al, spin):
    q = quat_from_tilt(th, al, spin)
    p = p_world(q)
    assert np.allclose(
        p, (math.sin(th) * math.cos(al), math.sin(th) * math.sin(al), math.cos(th)), atol=1e-12
    )
    assert np.allclose(quat_rotate(q, (0, 0, 1)), p, atol=1e-12)
    assert np.allclose(quat_to_matrix(q)[:, 2], p, atol=1e-12)
    t2, a2, s2 = tilt_from_quat(q)
    if 1e-6 < th < math.pi - 1e-6:
        assert math.isclose(t2, th, abs_tol=1e-9)
        assert abs(wrap(a2 - al)) < 1e-9
        assert quat_angle(quat_from_tilt(t2, a2, s2), q) < 1e-9


@FAST
@given(theta, angle, angle, radius, st.floats(0.0, 7.0), angle)
def test_straight_roll_by_theta_along_alpha_is_the_tilt_and_keeps_the_heading(th, al, spin, R, extra, psi):
    # Rolling a P-on-top sphere along α by θR gives quat_from_tilt(θ, α, spin).
    seg = GroundSegment(0.0, 0.0, al, th * R)
    assert quat_angle(roll_segment(quat_z(spin), seg, R), quat_from_tilt(th, al, spin)) < 1e-9
    # A full revolution is the identity; the heading survives tilting.
    rev = GroundSegment(0.0, 0.0, psi, 2 * math.pi * R)
    assert quat_angle(roll_segment(quat_from_tilt(th, al, spin), rev, R), quat_from_tilt(th, al, spin)) < 1e-9
    if th < math.pi - 1e-6:
        assert abs(wrap(heading_of(quat_from_tilt(th, al, spin)) - spin)) < 1e-9


@SLOW
@given(theta, angle, angle, radius, angle, st.floats(-3.0, 3.0), st.floats(0.01, 6.0))
def test_arc_closed_form_matches_fine_polyline_rolling(th, al, spin, R, h0, kR, length_r):
    q0 = quat_from_tilt(th, al, spin)
    seg = GroundSegment(0.3, -0.2, h0, length_r * R, kR / R)
    s = np.linspace(0.0, seg.length_m, 2001)
    x, y = seg.point_at(s)
    poly = roll_polyline(q0, np.column_stack([x, y]), R)
    closed = sample_segment(q0, seg, R, s[::200])
    for a, b in zip(closed, poly[::200], strict=True):
        assert quat_angle(tuple(a), tuple(b)) < 1e-5


@FAST
@given(theta, angle, angle, radius, angle, st.floats(-3.0, 3.0))
def test_arc_rolls_without_slip_and_without_vertical_spin(th, al, spin, R, h0, kR):
    """Finite differences of the closed form: ω has no z part and the contact point does not move."""
    q0 = quat_from_tilt(th, al, spin)
    seg = GroundSegment(0.0, 0.0, h0, 2.0 * R, kR / R)
    s = np.array([0.7 * R, 0.7 * R + 1e-6 * R])
    qa, qb = (tuple(v) for v in sample_segment(q0, seg, R, s))
    dq = quat_mul(qb, (qa[0], -qa[1], -qa[2], -qa[3]))  # rotation from a to b, world frame
    dq = dq if dq[0] >= 0 else tuple(-c for c in dq)
    omega = np.array(dq[1:]) * 2.0 / (s[1] - s[0])  # per metre travelled
    assert abs(omega[2]) < 1e-6 / R
    x, y = seg.point_at(s)
    v = np.array([x[1] - x[0], y[1] - y[0], 0.0]) / (s[1] - s[0])
    assert np.allclose(np.cross(omega, [0.0, 0.0, R]), v, atol=1e-5)


@SLOW
@given(st.floats(0.5, 1.2), angle, angle, radius, st.floats(-1.0, 1.0), st.floats(-1.0, 1.0))
def test_spherobot_model_eq_1_to_4_matches_so3_rolling(th, al, spin, R, wxp, wyp):
    """Integrate eq. 1–4 (RK4) and the full rotation (midpoint rule) under the same controls (ω'x, ω'y)."""
    dt, n = 0.002, 150
    state = SpherobotState(0.0, 0.0, th, al)
    q = quat_from_tilt(th, al, spin)
    xy = np.zeros(2)

    def model(s: SpherobotState) -> np.ndarray:
        return np.array(spherobot_rates(s, wxp, wyp, R))

    def add(s: SpherobotState, k: np.ndarray, h: float) -> SpherobotState:
        return SpherobotState(s.x + h * k[0], s.y + h * k[1], s.theta + h * k[2], s.alpha + h * k[3])

    def omega(qq: tuple[float, float, float, float]) -> np.ndarray:
        # ω_world = ω'x x' + ω'y y' with x' = (cos α, sin α, 0), y' = (−sin α, cos α, 0) from the current α
        _, a, _ = tilt_from_quat(qq)
        return np.array([wxp * math.cos(a) - wyp * math.sin(a), wxp * math.sin(a) + wyp * math.cos(a), 0.0])

    def turn(
        qq: tuple[float, float, float, float], w: np.ndarray, h: float
    ) -> tuple[float, float, float, float]:
        wn = float(np.linalg.norm(w))
        return qq if wn == 0 else quat_normalize(quat_mul(quat_axis_angle(tuple(w / wn), wn * h), qq))

    for _ in range(n):
        k1 = model(state)
        k2 = model(add(state, k1, dt / 2))
        k3 = model(add(state, k2, dt / 2))
        k4 = model(add(state, k3, dt))
        state = add(state, (k1 + 2 * k2 + 2 * k3 + k4) / 6, dt)
        w_mid = omega(turn(q, omega(q), dt / 2))
        q = turn(q, w_mid, dt)
        xy += np.cross(w_mid, [0.0, 0.0, R])[:2] * dt
    t2, a2, _ = tilt_from_quat(q)
    assert math.isclose(state.theta, t2, abs_tol=1e-5)
    assert abs(wrap(state.alpha - a2)) < 1e-5
    assert np.allclose([state.x, state.y], xy, atol=1e-5 * R)


@FAST
@given(st.floats(0.05, 1.5), angle, angle, radius, st.floats(0.1, 5.0), st.booleans())
def test_action_b_circle_of_radius_R_tan_theta_keeps_theta(th, al, spin, R, length_r, ccw):
    """Eq. 11: with ω'y = 0 the centre runs on a circle of radius R tan θ; θ stays, α turns with it."""
    sign = 1 if ccw else -1
    rho = R * math.tan(th)
    seg = GroundSegment(0.0, 0.0, al + sign * math.pi / 2, length_r * R, sign / rho, "b")
    q0 = quat_from_tilt(th, al, spin)
    wxp, wyp = model_controls(seg.heading_rad, 1.0, al, R)
    assert abs(wyp) < 1e-12 and math.isclose(abs(wxp), 1.0 / R)
    s = np.linspace(0, seg.length_m, 7)
    for si, q in zip(s, sample_segment(q0, seg, R, s), strict=True):
        t2, a2, _ = tilt_from_quat(tuple(q))
        assert math.isclose(t2, th, abs_tol=1e-9)
        assert abs(wrap(a2 - (al + sign * si / rho))) < 1e-9


def test_polyline_corner_is_a_pure_turn():
    q = roll_polyline(IDENTITY, np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], float), 1.0)
    assert q.shape == (5, 4)
    assert not np.allclose(q[-1], IDENTITY)  # a square on the ground is not closed on the sphere
    assert math.isclose(np.linalg.norm(q[-1]), 1.0)
