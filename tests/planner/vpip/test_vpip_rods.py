"""Rod driver (paper 000 eq. 4–18) checked against independent geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import InvalidInput, RobotProfileError
from planner.robot import load_robot
from planner.vpip.cascade import rod_params
from planner.vpip.rods import (
    RodDriver,
    RodParams,
    disc_centre,
    equivalent_plane,
    paper_angles,
    rod_direction,
    rod_lengths,
    rod_tips,
)

P = RodParams()


def _rot_y(a: float) -> np.ndarray:
    """Rotation about the paper's +y (forward) axis: +a lowers the right (+x) side."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_eq9_eq12_match_a_rotated_body() -> None:
    rng = np.random.default_rng(1)
    for _ in range(50):
        phi_r = rng.uniform(-0.4, 0.4)
        zeta = rng.uniform(0, 2 * math.pi, 5)
        side = rng.choice([-1.0, 1.0], 5)
        centre = np.array([0.0, 0.0, P.r_m])
        body_pm = np.stack([side * P.d_m_s, 0 * side, 0 * side], axis=-1)
        body_dir = np.stack([0 * zeta, -np.sin(zeta), -np.cos(zeta)], axis=-1)
        rot = _rot_y(phi_r)
        np.testing.assert_allclose(disc_centre(P, phi_r, side), centre + body_pm @ rot.T, atol=1e-12)
        np.testing.assert_allclose(rod_direction(phi_r, zeta), body_dir @ rot.T, atol=1e-12)
        # retracted tips (l = 0) lie on the shell: eq. 7
        tips = disc_centre(P, phi_r, side) + P.r_s * rod_direction(phi_r, zeta)
        np.testing.assert_allclose(np.linalg.norm(tips - centre, axis=1), P.r_m, atol=1e-12)


def test_random_planes_tips_on_plane_clamps_and_skips() -> None:
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(300):
        phi_v, theta_v = rng.uniform(-0.35, 0.35), rng.uniform(-0.7, 0.7)
        roll, phase = rng.uniform(-0.3, 0.3), rng.uniform(-10, 10)
        cmd = rod_lengths(P, phi_v, theta_v, roll, phase)
        pv, tv, _ = paper_angles(phi_v, theta_v, roll)
        # skipped rods are exactly those with zeta in (pi/2, 3pi/2), and they are retracted
        up = (cmd.zeta_rad > math.pi / 2) & (cmd.zeta_rad < 3 * math.pi / 2)
        assert np.array_equal(~cmd.active, up)
        assert np.all(cmd.length_m[up] == 0.0)
        # independent line-plane intersection: tip(l) = p_m + (r_s + l) u on tan(pv) x + tan(tv) y + z = 0
        normal = np.array([math.tan(pv), math.tan(tv), 1.0])
        pm = disc_centre(P, -roll, cmd.side)
        u = rod_direction(-roll, cmd.zeta_rad)
        lam = -(pm @ normal) / (u @ normal)
        l_geo = lam - P.r_s
        free = cmd.active & (cmd.clamped == 0)
        np.testing.assert_allclose(cmd.length_m[free], l_geo[free], atol=1e-9)
        tips = rod_tips(P, roll, cmd.zeta_rad, cmd.side, cmd.length_m)
        np.testing.assert_allclose(tips[free] @ normal, 0.0, atol=1e-9)  # eq. 4
        lo = cmd.active & (cmd.clamped == -1)
        hi = cmd.active & (cmd.clamped == 1)
        assert np.all(l_geo[lo] < 0) and np.all(cmd.length_m[lo] == 0.0)
        assert np.all(l_geo[hi] > P.l_max) and np.all(cmd.length_m[hi] == P.l_max)
        assert np.all((cmd.length_m >= 0) & (cmd.length_m <= P.l_max))
        checked += int(free.sum())
    assert checked > 300


def test_physical_meaning_of_the_angles() -> None:
    base = rod_lengths(P, 0.0, 0.0, 0.0, 0.3)
    fwd = rod_lengths(P, 0.0, math.radians(20), 0.0, 0.3)
    rear = base.active & (base.zeta_rad < math.pi / 2) & (base.clamped == 0)
    front = base.active & (base.zeta_rad > 3 * math.pi / 2) & (base.clamped == 0)
    assert rear.any() and front.any()
    assert np.all(fwd.raw_length_m[rear] > base.raw_length_m[rear])  # theta > 0: rear rods push
    assert np.all(fwd.raw_length_m[front] < base.raw_length_m[front])
    left = rod_lengths(P, math.radians(10), 0.0, 0.0, 0.3)
    bottom = base.active & (base.clamped == 0)
    is_left = base.side < 0
    assert np.all(left.raw_length_m[bottom & is_left] > base.raw_length_m[bottom & is_left])
    assert np.all(left.raw_length_m[bottom & ~is_left] < base.raw_length_m[bottom & ~is_left])
    # flat plane, upright: the rod straight down needs r_m - r_s to reach the ground
    down = rod_lengths(P, 0.0, 0.0, 0.0, 0.0)
    assert down.length_m[0] == pytest.approx(P.r_m - P.r_s)


def test_parallel_rod_holds_last_length() -> None:
    # zeta = 3pi/2 (horizontal, forward), flat plane, upright: D = cos(zeta) = 0
    prev = np.full(P.n_rods, 0.123)
    cmd = rod_lengths(P, 0.0, 0.0, 0.0, 0.0, prev)
    horizontal = np.isclose(cmd.zeta_rad, 1.5 * math.pi)
    assert horizontal.any() and np.all(cmd.held[horizontal])
    assert np.all(cmd.length_m[horizontal] == 0.123) and np.all(np.isnan(cmd.raw_length_m[horizontal]))


def test_driver_rate_limits_to_rod_speed() -> None:
    drv = RodDriver(P, 0.01)
    prev = drv.lengths_m.copy()
    for k in range(200):
        drv.step(math.radians(10) * math.sin(k / 7), math.radians(30), 0.05, 0.05 * k)
        assert np.max(np.abs(drv.lengths_m - prev)) <= P.rod_speed_m_s * 0.01 + 1e-15
        prev = drv.lengths_m.copy()


def test_equivalent_plane_recovers_a_plane() -> None:
    for phi, theta in ((math.radians(6), math.radians(16)), (math.radians(-10), math.radians(24))):
        cmd = rod_lengths(P, phi, theta, 0.02, 0.4)
        got = equivalent_plane(P, cmd.length_m, 0.02, 0.4, (math.radians(20), math.radians(40)))
        assert got[0] == pytest.approx(phi, abs=math.radians(1.1))
        assert got[1] == pytest.approx(theta, abs=math.radians(2.1))


def test_default_r_s_is_geometrically_sensible() -> None:
    p = rod_params(load_robot("daedalus"))
    assert p.d_m_s == pytest.approx(math.sqrt(p.r_m**2 - p.r_s**2))  # eq. 7
    assert p.r_s >= 0.07  # a retracted 0.07 m telescope segment fits in the disc
    assert p.push_window_rad >= 2 * math.pi / p.rods_per_side  # a rod per side always reaches the ground
    # the raised ring can still reach the ground at the profile's largest roll
    roll = load_robot("daedalus").max_roll_rad
    need = rod_lengths(p, 0.0, 0.0, roll, 0.0)  # rod 0 points straight down
    assert need.length_m[0] < p.l_max and need.length_m[p.rods_per_side] < p.l_max


def test_bad_inputs_name_the_field() -> None:
    with pytest.raises(InvalidInput, match="theta_vpip"):
        rod_lengths(P, 0.0, math.nan, 0.0)
    with pytest.raises(RobotProfileError, match=r"vpip\.r_s"):
        RodParams(r_s=0.3)
