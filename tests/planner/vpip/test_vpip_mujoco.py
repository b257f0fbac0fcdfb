"""The MuJoCo plant (paper 000 §4–5): geometry against eq. 4/12/18, and the physics claims that can fail."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from planner.errors import InvalidInput
from planner.robot import load_robot
from planner.synthetic_paths import plan_from_rolls
from planner.vpip.api import calibrate_from_circles
from planner.vpip.cascade import rod_params, run_schedule, vpip_section
from planner.vpip.circle import fit_circle, run_circle
from planner.vpip.mujoco_model import BodyParams
from planner.vpip.mujoco_plant import MujocoPlant, attitude, orientation_quat
from planner.vpip.rods import paper_angles, rod_lengths, rod_tips

DAEDALUS = load_robot("daedalus")
P = rod_params(DAEDALUS)
BODY = BodyParams.from_section(vpip_section(DAEDALUS))


def test_attitude_reads_back_the_pose_it_was_given() -> None:
    rng = np.random.default_rng(3)
    for _ in range(100):
        yaw, roll, phase = rng.uniform(-3, 3), rng.uniform(-1.2, 1.2), rng.uniform(-3, 3)
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, orientation_quat(yaw, roll, phase))
        got = attitude(mat)
        assert got[0] == pytest.approx(roll, abs=1e-9)
        assert math.remainder(got[1] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
        assert math.remainder(got[2] - phase, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def _pose(plant: MujocoPlant, x: float, y: float, yaw: float, roll: float, phase: float, lengths: np.ndarray) -> None:
    d = plant.data
    d.qpos[0:3] = (x, y, P.r_m)
    d.qpos[3:7] = orientation_quat(yaw, roll, phase)
    d.qpos[plant._rod_qpos] = lengths
    mujoco.mj_forward(plant.model, d)


def test_simulated_rod_tips_lie_on_the_vpip_when_commanded() -> None:
    """Eq. 18 lengths put the MuJoCo rod tips on the plane of eq. 4 (paper frame at the contact point)."""
    plant = MujocoPlant(P, BODY, settle_s=0.0)
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(60):
        phi_v, theta_v = rng.uniform(-0.3, 0.3), rng.uniform(-0.6, 0.6)
        roll, phase, yaw = rng.uniform(-0.25, 0.25), rng.uniform(-7, 7), rng.uniform(-3, 3)
        x, y = rng.uniform(-5, 5, 2)
        cmd = rod_lengths(P, phi_v, theta_v, roll, phase)
        _pose(plant, x, y, yaw, roll, phase, cmd.length_m)
        assert plant.observe().roll_rad == pytest.approx(roll, abs=1e-9)
        tips = plant.tip_positions() - np.array([x, y, 0.0])  # contact point at the origin
        forward = np.array([math.cos(yaw), math.sin(yaw), 0.0])
        right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
        paper = np.stack([tips @ right, tips @ forward, tips[:, 2]], axis=1)
        # the kinematic model of rods.py (eq. 9/12) and the simulated body agree for every rod
        np.testing.assert_allclose(paper, rod_tips(P, roll, cmd.zeta_rad, cmd.side, cmd.length_m), atol=1e-9)
        pv, tv, _ = paper_angles(phi_v, theta_v, roll)
        free = cmd.active & (cmd.clamped == 0)
        on_plane = paper[free] @ np.array([math.tan(pv), math.tan(tv), 1.0])
        np.testing.assert_allclose(on_plane, 0.0, atol=1e-9)  # eq. 4
        checked += int(free.sum())
    assert checked > 100


def test_rear_rods_extending_roll_the_sphere_forward() -> None:
    """θ_VPIP > 0 (rear rods extend, the corrected sign of eq. 4) makes the simulated sphere roll forward."""
    from planner.vpip.rods import RodDriver

    plant = MujocoPlant(P, BODY, yaw=0.7)
    drv = RodDriver(P, 0.01)
    for _ in range(300):
        o = plant.observe()
        drv.step(0.0, math.radians(25.0), o.roll_rad, o.phase_rad)
        plant.step(drv.lengths_m, 0.01)
    o = plant.observe()
    assert o.phase_rad > 1.0  # rolled more than a radian forward
    moved = np.array([o.x, o.y])
    assert moved @ np.array([math.cos(0.7), math.sin(0.7)]) > 0.2  # along the heading it started with
    assert o.phase_rad * P.r_m == pytest.approx(np.linalg.norm(moved), rel=0.15)  # rolling, not sliding


@pytest.fixture(scope="module")
def short_circles() -> dict[int, dict]:
    """9 s held-roll runs (3 s settling) at 5°, 15° and −15° on the MuJoCo plant (the profile's defaults:
    regolith contact, rod-rate gains), shared by the tests below."""
    return {r: run_circle(DAEDALUS, math.radians(r), duration_s=9.0, settle_s=3.0)["summary"] for r in (5, 15, -15)}


def test_held_roll_turns_the_right_way_and_tighter_with_more_roll(short_circles: dict[int, dict]) -> None:
    """A held roll > 0 turns left, < 0 right; 15° turns tighter than 5° (short runs, physics only)."""
    runs = short_circles
    k = {r: math.radians(s["turned_deg"]) / s["path_length_m"] for r, s in runs.items()}
    assert k[15] > 0 and k[5] > 0 and k[-15] < 0
    assert k[15] > 1.5 * k[5]
    for s in runs.values():
        assert s["path_length_m"] > 0.3
        assert s["diameter_source"].startswith("MuJoCo")
        assert s["max_rod_length_m"] <= P.l_max + 1e-3  # slide-joint limit (soft constraint, < 1 mm)
        assert s["commanded_rod_rate"]["max_m_s"] <= P.rod_speed_m_s + 1e-9
        # the plant's rods move at the commanded 0.1 m/s; a load only back-drives the velocity servo briefly
        assert s["measured_rod_rate"]["p95_m_s"] <= 1.01 * P.rod_speed_m_s
        assert s["measured_rod_rate"]["max_m_s"] <= 1.4 * P.rod_speed_m_s


def test_no_rod_servo_can_be_asked_to_move_faster_than_the_rod_speed() -> None:
    """docs/vpip.md "The operating point": the velocity servos' command range is Table 1's ±0.1 m/s."""
    plant = MujocoPlant(P, BODY, settle_s=0.0)
    ranges = plant.model.actuator_ctrlrange
    assert ranges.shape == (P.n_rods, 2)
    np.testing.assert_allclose(ranges, [[-P.rod_speed_m_s, P.rod_speed_m_s]] * P.n_rods)
    assert not plant.model.actuator_forcelimited.any()  # a self-locking screw: loads do not run it backwards


def test_the_turn_is_the_tilt_of_a_rolling_sphere_not_spin(short_circles: dict[int, dict]) -> None:
    """docs/vpip.md "The turn explained": heading rate = spin Ω_z + ω_h·tan(roll), and on the regolith contact
    the spin is small, so the circle is set by the roll held (≈ 2r/tan(roll), never much tighter)."""
    for r, s in short_circles.items():
        # the split is kinematics of the simulated body: it must add up to the measured heading rate
        assert s["mean_yaw_rate_rad_s"] == pytest.approx(
            s["mean_spin_rad_s"] + s["mean_no_spin_yaw_rate_rad_s"], abs=5e-3
        )
        tilt = s["mean_no_spin_yaw_rate_rad_s"]
        assert math.copysign(1.0, tilt) == math.copysign(1.0, r)
        assert abs(s["mean_spin_rad_s"]) < 0.3 * abs(tilt)  # spin would be what makes circles tighter
        # the shell rolls, it does not skid: the centre moves at about r·ω (lateral rocking adds a little)
        assert s["mean_speed_m_s"] == pytest.approx(P.r_m * s["mean_omega_rad_s"], rel=0.35)
        # issue 24: on the regolith contact the circle is what the split says, 2r / (tan φ_held + Ω_z/ω_h)
        if abs(r) == 15:
            assert s["diameter_m"] == pytest.approx(s["spin_lean_diameter_m"], rel=0.15)
    s15 = short_circles[15]
    # hypothesis (a) of docs/vpip.md: the rod feet do reach the floor, beside and behind the shell's contact
    feet = s15["rod_feet"]
    assert 0.05 < feet["ticks_with_a_foot_down_fraction"] < 0.6
    assert feet["low"]["mean_lateral_m"] < -0.1 and feet["high"]["mean_lateral_m"] > 0.1  # leaning left
    assert feet["low"]["mean_forward_m"] < 0 and feet["high"]["mean_forward_m"] < 0
    assert 2.0 * s15["mean_speed_m_s"] / s15["mean_yaw_rate_rad_s"] > 0.8 * s15["no_spin_diameter_m"]


def test_with_the_paper_simulators_contact_15deg_spins_into_the_turn_and_lands_near_the_paper() -> None:
    """docs/vpip.md: with the paper's Gazebo contact (no slip, no spin friction) the sphere spins with the turn
    (Ω_z > 0), which is what lets a circle be tighter than 2r/tan(roll); at 15° the fitted circle is then within
    30 % of the paper's 1.7 m, at the paper's operating point (12 s run, 9 s fitted: a short window, so the band is
    the issue's 30 %, not tighter)."""
    s = run_circle(DAEDALUS, math.radians(15), duration_s=12.0, settle_s=3.0, contact="paper")["summary"]
    assert s["contact"] == "paper"
    assert s["mean_spin_rad_s"] > 0.005
    assert s["mean_yaw_rate_rad_s"] > s["mean_no_spin_yaw_rate_rad_s"]
    assert s["diameter_m"] is not None
    assert s["diameter_m"] < s["no_spin_diameter_m"]
    assert 0.7 * 1.7 <= s["diameter_m"] <= 1.3 * 1.7
    assert s["mean_omega_rad_s"] == pytest.approx(1.0, abs=0.2)
    assert s["held_roll_deg"] == pytest.approx(15.0, abs=1.5)


def test_table1_roll_pid_rides_its_limits_and_the_rod_rate_gains_hold_the_operating_point(
    short_circles: dict[int, dict],
) -> None:
    """docs/vpip.md "The operating point". Table 1's gains on 0.1 m/s rods: k_d = 3.5 turns the rod-driven roll
    rates into far more than the ±20° output limit, φ_VPIP mostly sits at a limit (tilting the plane 7 cm at the
    discs, so one ring's rods never reach the ground), the integral part sits at its 5° limit and the roll is held
    short; ω stalls near 0.6 rad/s. The rod-rate gains never saturate, hold the roll and reach ω ≈ 1 rad/s."""
    s = run_circle(DAEDALUS, math.radians(15), duration_s=9.0, settle_s=3.0, gains="table1")["summary"]
    pid = s["roll_pid"]
    assert s["gains"] == "table1"
    assert pid["output_saturated_fraction"] > 0.5
    assert pid["rms_derivative_part_deg"] > 20.0
    assert pid["integral_at_limit_fraction"] > 0.5
    assert abs(s["mean_roll_deg"]) < 15 - 2.0  # held short of the target
    assert s["mean_omega_rad_s"] < 0.8
    for r, run in short_circles.items():
        assert run["gains"] == "rod-rate"
        assert run["roll_pid"]["output_saturated_fraction"] < 0.05
        assert run["held_roll_deg"] == pytest.approx(r, abs=1.5)
        assert run["mean_omega_rad_s"] == pytest.approx(1.0, abs=0.2)


def test_mujoco_schedule_keeps_rods_within_limits_and_follows_an_arc() -> None:
    plan = plan_from_rolls(DAEDALUS, [(0.3, 0.0), (1.2, math.radians(10.0))], speed_m_s=0.12)
    out = run_schedule(plan, DAEDALUS, plant="mujoco", max_duration_s=12.0)
    s, summ = out["series"], out["summary"]
    assert out["plant"]["kind"] == "mujoco" and summ["plant"] == "mujoco"
    cmd = np.asarray(s["rod_length_m"])
    meas = np.asarray(s["rod_measured_m"])
    dt = 1.0 / out["rate_hz"]
    assert np.max(np.abs(np.diff(cmd, axis=0))) <= P.rod_speed_m_s * dt + 1e-12
    assert np.all((cmd >= 0) & (cmd <= P.l_max))
    assert meas.min() >= -1e-3 and meas.max() <= P.l_max + 1e-3
    # the servo follows the rate-limited command: the measured per-tick rate stays near the limit
    assert summ["measured_rod_rate"]["p95_m_s"] <= 1.05 * P.rod_speed_m_s
    assert np.max(np.abs(meas - cmd)) < 0.05
    # the sphere made headway along the plan and turned left with it
    assert s["s"][-1] > 0.5
    assert np.unwrap(s["yaw"])[-1] - s["yaw"][0] > math.radians(10)
    assert summ["rms_lateral_error_m"] < 0.3


def test_fit_circle_recovers_an_arc() -> None:
    rng = np.random.default_rng(2)
    a = np.linspace(0.3, 2.5, 200)
    x, y = 1.0 + 1.3 * np.cos(a) + rng.normal(0, 0.005, a.size), -2.0 + 1.3 * np.sin(a)
    cx, cy, r, resid = fit_circle(x, y)
    assert (cx, cy, r) == pytest.approx((1.0, -2.0, 1.3), abs=0.01)
    assert resid < 0.01


def test_calibrate_from_circles_builds_the_table_and_names_bad_runs() -> None:
    runs = [
        {"summary": {"roll_desired_deg": 5.0, "diameter_m": 6.0, "plant": "mujoco"}},
        {"summary": {"roll_desired_deg": -5.0, "diameter_m": 4.0, "plant": "mujoco"}},
        {"summary": {"roll_desired_deg": 15.0, "diameter_m": 2.5, "plant": "mujoco"}},
    ]
    out = calibrate_from_circles(runs, DAEDALUS)
    assert out["roll_model"]["roll_deg"] == [5.0, 15.0]
    assert out["roll_model"]["diameter_m"][0] == pytest.approx(2 / (0.5 * (1 / 3.0 + 1 / 2.0)))
    assert "mujoco" in out["source"]
    with pytest.raises(InvalidInput, match=r"circles\[1\]\.summary\.diameter_m"):
        calibrate_from_circles([runs[0], {"summary": {"roll_desired_deg": 10.0, "diameter_m": None}}], DAEDALUS)
    with pytest.raises(InvalidInput, match="circles"):
        calibrate_from_circles([runs[2], {"summary": {"roll_desired_deg": 20.0, "diameter_m": 3.0}}], DAEDALUS)


def test_bad_circle_input_names_the_field() -> None:
    with pytest.raises(InvalidInput, match="roll"):
        run_circle(DAEDALUS, math.radians(30), 5.0)
    with pytest.raises(InvalidInput, match="plant"):
        run_circle(DAEDALUS, 0.1, 5.0, plant="gazebo")
    with pytest.raises(InvalidInput, match="duration"):
        run_circle(DAEDALUS, 0.1, -1.0)
    with pytest.raises(InvalidInput, match="theta_vpip"):
        run_circle(DAEDALUS, 0.1, 5.0, theta_vpip_rad=math.radians(60))
