"""The pendulum-sphere plant (paper 001 eq. 16–19, derived in planner/pendulum/dynamics.py) against physics.

Energy is conserved without damping and actuation (yaw coupling included), the motors' work equals the
energy change, the eq. 20 linearisation matches finite differences of the nonlinear model (at rest and,
for roll, about rolling straight) and a small-signal simulation, both linear models are controllable,
and the steady states the controllers rely on are those of the plant.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from planner.errors import RobotProfileError
from planner.pendulum.dynamics import (
    G,
    PendulumSpherePlant,
    controllability_rank,
    linear_model,
    params_from_profile,
)
from planner.robot import load_robot, profile_from_dict

ROBOTS = ("zju-60", "zju-80")


def _params(name: str = "zju-60"):
    return params_from_profile(load_robot(name))


def _lossless(name: str = "zju-60", yaw: bool = True) -> PendulumSpherePlant:
    return PendulumSpherePlant(_params(name), yaw_coupling=yaw).without_losses()


@pytest.mark.parametrize("name", ROBOTS)
def test_energy_is_conserved_without_damping_and_actuation(name: str) -> None:
    """Large swings, rolling and turning at once: the yaw-coupling terms must do no work."""
    plant = _lossless(name)
    s0 = np.array([0.4, 0.8, 0.0, 1.2, -0.3, 0.5, 0.15, -0.2, 0.0, 0.0, 0.3])
    sol = solve_ivp(lambda t, s: plant.rhs(s, 0.0, 0.0), (0.0, 4.0), s0, rtol=1e-10, atol=1e-12)
    energies = [plant.energy(sol.y[:, i]) for i in range(sol.y.shape[1])]
    e0 = plant.energy(s0)
    assert e0 > 1.0
    assert max(abs(e - e0) for e in energies) < 1e-6 * e0
    # and the motion is not trivial: energy moves between pendulum and shell, the robot turns
    assert abs(sol.y[0, -1] - s0[0]) > 0.05 and abs(sol.y[10, -1] - s0[10]) > 0.01


def test_rk4_step_keeps_energy_over_many_periods() -> None:
    plant = _lossless()
    s = np.array([0.3, 0.0, 0.0, 0.8, 0.2, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0])
    e0 = plant.energy(s)
    for _ in range(500):  # 10 s at 50 Hz
        s = plant.step(s, 0.0, 0.0, 0.02)
    assert plant.energy(s) == pytest.approx(e0, rel=1e-5)


def test_motor_work_minus_losses_equals_energy_change() -> None:
    """dE/dt = τ_p(α̇ + ṡ_p) + τ_r(β̇ + φ̇) − dissipation: the input matrix E = [1 1]ᵀ of eq. 17."""
    plant = PendulumSpherePlant(_params(), floor="rubber")

    def tau(t: float) -> tuple[float, float]:
        return 4.0 * math.sin(2.0 * t), 3.0 * math.cos(3.0 * t)

    def f(t: float, x: np.ndarray) -> list[float]:
        tp, tr = tau(t)
        return [*plant.rhs(x[:11], tp, tr), plant.power(x[:11], tp, tr)]

    s0 = [0.1, 0.0, 0.0, 0.5, 0.05, 0.0, 0.05, 0.1, 0.0, 0.0, 0.0]
    sol = solve_ivp(f, (0.0, 3.0), [*s0, 0.0], rtol=1e-10, atol=1e-12)
    end = sol.y[:, -1]
    assert plant.energy(end[:11]) - plant.energy(s0) == pytest.approx(end[11], abs=1e-6)
    # the losses are real: without the motors the same start loses energy
    free = solve_ivp(lambda t, x: plant.rhs(x, 0.0, 0.0), (0.0, 3.0), s0, rtol=1e-9, atol=1e-11)
    assert plant.energy(free.y[:, -1]) < plant.energy(s0) - 0.1


@pytest.mark.parametrize("name", ROBOTS)
def test_linearisation_matches_finite_differences_at_rest(name: str) -> None:
    """Eq. 20's A_c, B_c (derived) = the Jacobian of the nonlinear model at rest (no rolling resistance,
    whose smooth law is steep at v = 0; eq. 20 carries it as the constant V_c instead)."""
    p = dataclasses.replace(_params(name), rolling_resistance={"tiled": 0.0})
    plant = PendulumSpherePlant(p)
    x0 = np.zeros(11)
    jac = np.zeros((11, 11))
    h = 1e-6
    for i in range(11):
        e = np.zeros(11)
        e[i] = h
        jac[:, i] = (np.array(plant.rhs(x0 + e, 0.0, 0.0)) - np.array(plant.rhs(x0 - e, 0.0, 0.0))) / (2 * h)
    b_num = (np.array(plant.rhs(x0, 1e-3, 0.0)) - np.array(plant.rhs(x0, -1e-3, 0.0))) / 2e-3
    b_roll = (np.array(plant.rhs(x0, 0.0, 1e-3)) - np.array(plant.rhs(x0, 0.0, -1e-3))) / 2e-3
    pitch, roll = linear_model(p, "pitch"), linear_model(p, "roll")
    np.testing.assert_allclose(jac[0:4, 0:4], pitch.a, atol=1e-6)
    np.testing.assert_allclose(jac[4:8, 4:8], roll.a, atol=1e-6)
    np.testing.assert_allclose(b_num[0:4], pitch.b, atol=1e-8)
    np.testing.assert_allclose(b_roll[4:8], roll.b, atol=1e-8)
    assert np.abs(jac[0:4, 4:8]).max() < 1e-9 and np.abs(jac[4:8, 0:4]).max() < 1e-9  # decoupled at rest


def test_roll_linearisation_about_rolling_straight() -> None:
    """linear_model(speed=v) has the yaw coupling's stiffness: it matches the plant's Jacobian at speed."""
    p = dataclasses.replace(_params(), rolling_resistance={"tiled": 0.0})
    plant = PendulumSpherePlant(p)
    for v in (0.5, 1.5):
        tau_p = p.damping_pitch_n_m_s * v / p.radius_m
        x0 = np.zeros(11)
        x0[0], x0[3] = math.asin(tau_p / p.gravity_torque_n_m), v
        jac = np.zeros((4, 4))
        for j, i in enumerate(range(4, 8)):
            e = np.zeros(11)
            e[i] = 1e-6
            diff = np.array(plant.rhs(x0 + e, tau_p, 0.0)) - np.array(plant.rhs(x0 - e, tau_p, 0.0))
            jac[:, j] = diff[4:8] / 2e-6
        lin = linear_model(p, "roll", speed=v)
        np.testing.assert_allclose(jac, lin.a, rtol=6e-3, atol=1e-3)  # cos α_ss ≈ 1 in the model
        assert lin.a[3, 2] < -0.5 * v * v  # the roll is pulled back upright at speed


def test_rolling_resistance_is_eq20s_constant_vc_when_moving() -> None:
    p = _params()
    plant = PendulumSpherePlant(p)
    lin = linear_model(p, "pitch", forward=1.0)
    x = np.zeros(11)
    x[3] = 1.0  # 1 m/s ≫ the smoothing speed
    for tau in (-2.0, 0.0, 3.0):
        f = np.array(plant.rhs(x, tau, 0.0))[0:4]
        lin_f = lin.a @ x[0:4] + lin.b * tau + lin.v
        np.testing.assert_allclose(f, lin_f, atol=2e-3 * np.abs(lin.v).max() + 1e-9)


def _small_signal_error(amplitude: float) -> float:
    p = dataclasses.replace(_params(), rolling_resistance={"tiled": 0.0})
    plant = PendulumSpherePlant(p)
    pitch, roll = linear_model(p, "pitch"), linear_model(p, "roll")
    ap, bp, _ = pitch.discretise(0.01)
    ar, br, _ = roll.discretise(0.01)
    s = np.zeros(11)
    xp, xr = np.zeros(4), np.zeros(4)
    err, scale = 0.0, 0.0
    for k in range(150):
        tp = amplitude * math.sin(3.0 * k * 0.01)
        tr = 0.7 * amplitude * math.cos(5.0 * k * 0.01)
        s = plant.step(s, tp, tr, 0.01, substeps=2)
        xp, xr = ap @ xp + bp * tp, ar @ xr + br * tr
        err = max(err, float(np.abs(s[[0, 4]] - [xp[0], xr[0]]).max()))
        scale = max(scale, float(np.abs([xp[0], xr[0]]).max()))
    return err / scale


def test_linear_model_tracks_the_plant_near_rest_and_the_gap_is_higher_order() -> None:
    small, large = _small_signal_error(0.25), _small_signal_error(1.0)
    assert small < 0.005
    # a wrong A or B would give an amplitude-independent relative error; the model's nonlinearities are
    # odd (sin a, ȧ² sin a, …), so the relative gap grows with the amplitude squared: 4× → 16×
    assert 10.0 < large / small < 25.0


@pytest.mark.parametrize("name", ROBOTS)
def test_linear_models_are_controllable(name: str) -> None:
    p = _params(name)
    for sub in ("pitch", "roll"):
        lin = linear_model(p, sub)
        assert controllability_rank(lin.a, lin.b) == 4
    # the RSLQR's integral-augmented roll model too (eq. 28)
    lin = linear_model(p, "roll")
    a = np.zeros((5, 5))
    a[0, 3] = 1.0
    a[1:, 1:] = lin.a
    assert controllability_rank(a, np.concatenate([[0.0], lin.b])) == 5


def test_a_torque_first_rolls_the_shell_backwards() -> None:
    """The pendulum's reaction: the non-minimum-phase start the controllers must live with."""
    p = _params()
    for sub in ("pitch", "roll"):
        lin = linear_model(p, sub)
        assert lin.b[3] < 0 < lin.b[1]
    plant = PendulumSpherePlant(p)
    s = np.zeros(11)
    for _ in range(5):
        s = plant.step(s, 5.0, 0.0, 0.02)
    assert s[3] < 0 < s[0]
    for _ in range(50):
        s = plant.step(s, 5.0, 0.0, 0.02)
    assert s[3] > 0.1  # then it rolls forward


def test_euler_discretisation_of_eq21_would_be_unstable_at_50hz() -> None:
    p = dataclasses.replace(_params(), damping_pitch_n_m_s=0.0, rolling_resistance={"tiled": 0.0})
    lin = linear_model(p, "pitch")
    euler = np.eye(4) + lin.a * 0.02
    zoh, _, _ = lin.discretise(0.02)
    assert max(abs(np.linalg.eigvals(euler))) > 1.01
    assert max(abs(np.linalg.eigvals(zoh))) < 1.0 + 1e-9


def test_pitch_equilibrium_holds_the_speed() -> None:
    plant = PendulumSpherePlant(_params(), floor="rubber")
    s = plant.rolling_state(1.2)
    _, tau = plant.pitch_equilibrium(1.2)
    for _ in range(100):
        s = plant.step(s, tau, 0.0, 0.02)
    assert s[3] == pytest.approx(1.2, abs=1e-6)
    assert s[8] == pytest.approx(2.4, abs=1e-3)


def test_profiles_carry_documented_dynamics() -> None:
    for name in ROBOTS:
        p = _params(name)
        assert p.pendulum_length_m < p.radius_m
        assert p.max_torque_pitch_n_m < p.gravity_torque_n_m  # the pendulum cannot be driven over the top
        assert set(p.rolling_resistance) == {"tiled", "rubber"}
        assert p.total_mass_kg * G > 0
    assert _params("zju-80").total_mass_kg > _params("zju-60").total_mass_kg
    data = {
        "name": "bad", "radius_m": 0.3, "max_roll_deg": 15, "max_roll_rate_deg_s": 30, "roll_time_constant_s": 0.2,
        "max_speed_m_s": 0.5, "max_accel_m_s2": 0.5, "footprint_length_m": 0.6, "footprint_width_m": 0.6,
        "dynamics": dict(load_robot("zju-60").extra["dynamics"]),
    }
    data["dynamics"]["pendulum_mass_kg"] = -1.0
    with pytest.raises(RobotProfileError, match=r"dynamics\.pendulum_mass_kg"):
        params_from_profile(profile_from_dict(data))
    with pytest.raises(RobotProfileError, match="dynamics"):
        params_from_profile(load_robot("daedalus"))
