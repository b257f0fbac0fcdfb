"""Invariants of the closed-form statics (paper 002 §II–III), checked against geometry and physics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import InvalidInput
from planner.robot import load_robot
from planner.tensegrity import static_equilibria
from planner.tensegrity.energy import angle_deg, potential_energy
from planner.tensegrity.geometry import (
    R12,
    G,
    TexplorParams,
    centre_of_mass,
    link_point,
    link_tangent,
    lowest_depth,
    mass_points,
    params_from_profile,
)
from planner.tensegrity.statics import equilibria, paper_contact_angle

PARAMS = params_from_profile(load_robot("texplor"))
GRID = [(t1, t2) for t1 in np.linspace(0.05, math.pi - 0.05, 11) for t2 in np.linspace(0.0, math.pi, 11)]


def test_profile_masses_and_radius() -> None:
    assert PARAMS.radius_m == pytest.approx(0.2015)
    assert PARAMS.slider_mass_kg == (0.427, 0.427)
    assert PARAMS.link_mass_kg == (0.431, 0.431)


def test_link_two_is_link_one_turned_by_r12() -> None:
    for a in np.linspace(0, math.pi, 7):
        assert np.allclose(link_point(2, a, 1.0), R12 @ link_point(1, a, 1.0))
        assert np.allclose(link_tangent(2, a, 1.0), R12 @ link_tangent(1, a, 1.0))


def test_lowest_depth_matches_dense_sampling() -> None:
    rng = np.random.default_rng(3)
    alpha = np.linspace(0, math.pi, 20001)
    arcs = np.concatenate([np.stack([link_point(k, a, 0.2) for a in alpha]) for k in (1, 2)])
    for _ in range(50):
        up = rng.normal(size=3)
        up /= np.linalg.norm(up)
        assert float(lowest_depth(up, 0.2)) == pytest.approx(float(np.max(arcs @ -up)), abs=1e-8)


@pytest.mark.parametrize(("theta1", "theta2"), GRID)
def test_feasible_states_rest_on_the_ground(theta1: float, theta2: float) -> None:
    r = PARAMS.radius_m
    feasible = [s for s in equilibria(theta1, theta2, PARAMS, verify=False) if s.feasible]
    assert feasible, "some state always exists"
    for s in feasible:
        z_s = s.r_sb @ s.z_b
        assert np.allclose(z_s, [0, 0, 1])
        q1, q2 = link_point(1, s.phi1_rad, r), link_point(2, s.phi2_rad, r)
        world = [s.o_sb_m + s.r_sb @ q for q in (q1, q2)]
        # both contacts on one plane, r/sqrt(2) below the centre, and nothing of the body below it
        assert world[0][2] == pytest.approx(0.0, abs=1e-12)
        assert world[1][2] == pytest.approx(0.0, abs=1e-12)
        assert float(lowest_depth(s.z_b, r)) == pytest.approx(r / math.sqrt(2), abs=1e-12)
        # the rolling link is tangent to the ground at its contact
        link = 1 if s.state in (1, 2) else 2
        angle = s.phi1_rad if link == 1 else s.phi2_rad
        assert float(s.z_b @ link_tangent(link, angle, r)) == pytest.approx(0.0, abs=1e-12)
        # the centre of mass lies in the vertical plane through the two contacts
        normal = np.cross(s.z_b, q1 - q2)
        assert float(normal @ (centre_of_mass(theta1, theta2, PARAMS) - q2)) == pytest.approx(0.0, abs=1e-12)
        # forces: non-negative, sum to the weight, and balance the moments (3-D, about O_b)
        f1, f2 = s.forces_n
        assert f1 >= 0 and f2 >= 0
        assert f1 + f2 == pytest.approx(PARAMS.total_mass_kg * G)
        points, masses = mass_points(theta1, theta2, PARAMS)
        moment = sum(m * G * np.cross(p, -s.z_b) for p, m in zip(points, masses, strict=True))
        moment = moment + f1 * np.cross(q1, s.z_b) + f2 * np.cross(q2, s.z_b)
        assert np.allclose(moment, 0.0, atol=1e-9)


@pytest.mark.parametrize(("theta1", "theta2"), GRID[::7])
def test_closed_form_equals_energy_minimum(theta1: float, theta2: float) -> None:
    for s in equilibria(theta1, theta2, PARAMS):
        assert s.verified, (s.state, s.feasible, s.energy_min_deg_error)
        if s.feasible:
            assert s.energy_min_deg_error < 1e-3


def test_every_energy_minimum_is_a_closed_form_state() -> None:
    profile = load_robot("texplor")
    result = static_equilibria(math.radians(30), math.radians(100), profile)
    assert result["verified"]
    feasible = {s["state"] for s in result["states"] if s["feasible"]}
    assert {m["state"] for m in result["energy_minima"]} == feasible


def test_equal_masses_reduce_to_the_paper_tan_formula() -> None:
    for theta1, theta2 in GRID:
        for s in equilibria(theta1, theta2, PARAMS, verify=False):
            if (
                s.feasible
                and not s.reason
                and 1e-6 < (s.phi1_rad if s.state < 3 else s.phi2_rad) < math.pi - 1e-6
            ):
                mine = s.phi1_rad if s.state < 3 else s.phi2_rad
                assert mine == pytest.approx(paper_contact_angle(s.state, theta1, theta2), abs=1e-12)


def test_rolling_links_split_the_slider_plane() -> None:
    # sin θ1 > sin θ2: the centre of mass is on link 1's side, so only states 1, 2 rest
    states = {
        s.state for s in equilibria(math.radians(80), math.radians(20), PARAMS, verify=False) if s.feasible
    }
    assert states == {1, 2}
    states = {
        s.state for s in equilibria(math.radians(20), math.radians(80), PARAMS, verify=False) if s.feasible
    }
    assert states == {3, 4}


def test_unequal_masses_agree_with_energy_and_keep_forces_positive() -> None:
    rng = np.random.default_rng(11)
    for _ in range(6):
        params = TexplorParams(0.2, tuple(rng.uniform(0.1, 3.0, 2)), tuple(rng.uniform(0.05, 1.0, 2)))
        theta1, theta2 = rng.uniform(0.0, math.pi, 2)
        sols = equilibria(theta1, theta2, params)
        assert any(s.feasible for s in sols)
        for s in sols:
            assert s.verified, (s.state, s.feasible, s.energy_min_deg_error)
            if s.feasible:
                assert min(s.forces_n) >= 0.0


def test_potential_energy_is_lowest_at_feasible_states() -> None:
    rng = np.random.default_rng(7)
    for s in equilibria(math.radians(60), math.radians(10), PARAMS, verify=False):
        if not s.feasible:
            continue
        e0 = float(potential_energy(s.z_b, math.radians(60), math.radians(10), PARAMS))
        for _ in range(200):
            u = s.z_b + rng.normal(scale=0.02, size=3)
            assert float(potential_energy(u, math.radians(60), math.radians(10), PARAMS)) >= e0 - 1e-12
            assert angle_deg(u, s.z_b) > 0


def test_slider_angle_off_the_arc_is_rejected() -> None:
    with pytest.raises(InvalidInput, match="theta1"):
        equilibria(-0.5, 1.0, PARAMS)
    with pytest.raises(InvalidInput, match="theta2"):
        equilibria(0.5, 4.0, PARAMS)
