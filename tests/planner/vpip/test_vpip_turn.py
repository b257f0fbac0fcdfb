"""The assumption behind "a circle tighter than 2r/tan(roll) needs spin", checked with a second model.

docs/vpip.md "The turn explained": heading rate = Ω_z + ω_h·tan(roll), so a sphere that rolls without slip
and without spin (Ω_z = 0) rolls the circle D = 2r/tan(roll), whatever pushes it. The MuJoCo runs measure
that split on the simulated body (``MujocoPlant.turn_rates``); this test checks the no-spin circle with an
independent model: paper 004's SO(3) rolling (:func:`planner.spherobot.rolling.roll_polyline`, pure rolling,
no spin about the vertical), which knows nothing about rods, roll or MuJoCo.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.spherobot.rolling import quat_to_matrix, roll_polyline

R = 0.232


def _axle_along_circle(diameter_m: float, tilt_rad: float) -> np.ndarray:
    """Roll once around a circle (left turn) with no spin; the world direction of the body axle that started
    pointing left, lowered on the left by ``tilt_rad`` (the robot leaning left), at every vertex, shape (N, 3)."""
    rho = 0.5 * diameter_m
    a = np.linspace(0.0, 2.0 * math.pi, 20001)
    xy = np.c_[rho * np.sin(a), rho * (1.0 - np.cos(a))]  # starts at the origin heading +x, centre on the left
    quats = roll_polyline((1.0, 0.0, 0.0, 0.0), xy, R)
    axle0 = np.array([0.0, math.cos(tilt_rad), -math.sin(tilt_rad)])
    return np.array([quat_to_matrix(tuple(q)) @ axle0 for q in quats[::500]])


@pytest.mark.parametrize("roll_deg", [5.0, 10.0, 15.0])
def test_a_sphere_rolling_without_spin_holds_its_lean_only_on_the_circle_2r_over_tan_roll(roll_deg: float) -> None:
    phi = math.radians(roll_deg)
    on = _axle_along_circle(2.0 * R / math.tan(phi), phi)
    # on D = 2r/tan(roll) the lean is held all the way round: the axle keeps its tilt and stays across the path
    assert np.allclose(on[:, 2], -math.sin(phi), atol=1e-3)
    # the paper's diameters are tighter than that at 5 and 10 deg: there, a non-spinning sphere cannot keep its
    # lean (the axle tilt wanders by degrees), which is why the paper's circles need spin into the turn
    paper = {5.0: 2.6, 10.0: 2.0, 15.0: 1.7}[roll_deg]
    if paper < 0.9 * 2.0 * R / math.tan(phi):
        off = _axle_along_circle(paper, phi)
        assert np.max(np.abs(np.degrees(np.arcsin(-off[:, 2])) - roll_deg)) > 2.0
