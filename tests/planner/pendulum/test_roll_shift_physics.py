"""The sideways shift of a roll change, r·Δφ (paper 001 eq. 1), in an independent physics engine.

The planner charges every roll change its shift (:func:`planner.kinematics.roll_shift`) and counts it in a
path's length; a Dubins or Reeds–Shepp car's length does not (issue 21's twentieth round: the real bench's
``÷rolled`` and ``÷1st rolled`` columns rest on it). Here a pendulum sphere is built in MuJoCo from nothing but
its shell, a pendulum hinged about the forward axis and a floor with friction. At rest, the pendulum motor swings
the pendulum sideways relative to the shell; the shell rolls until the pendulum hangs straight down again, and
the centre moves sideways by the shell's radius × its roll change, the sign eq. 1 gives (ẏ = r φ̇ cos θ at θ = 0
for a roll φ about the forward axis x, here measured as the shell's rotation about x, which rolls it towards −y).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from planner.kinematics import roll_shift
from planner.robot import load_robot


def _sphere(radius: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
    xml = f"""
    <mujoco>
      <option timestep="0.0005" gravity="0 0 -9.81" integrator="implicitfast"/>
      <worldbody>
        <geom type="plane" size="5 5 0.1" friction="1.5 0.005 0.0001"/>
        <body name="shell" pos="0 0 {radius}">
          <joint type="free" damping="0.3"/>
          <geom type="sphere" size="{radius}" mass="2.0" friction="1.5 0.005 0.0001"/>
          <body name="pendulum">
            <joint name="swing" type="hinge" axis="1 0 0" damping="2"/>
            <geom type="sphere" pos="0 0 {-0.6 * radius}" size="{0.2 * radius}" mass="4.0" contype="0"
                  conaffinity="0"/>
          </body>
        </body>
      </worldbody>
      <actuator><position joint="swing" kp="400" kv="20"/></actuator>
    </mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model)


def _shell_roll(data: mujoco.MjData) -> float:
    """The shell's rotation about the world x axis (its forward axis at rest), from its quaternion."""
    w, x, y, z = data.qpos[3:7]
    return math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))


def _settle(model: mujoco.MjModel, data: mujoco.MjData, seconds: float) -> None:
    for _ in range(int(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)


def test_a_roll_change_at_rest_moves_the_centre_sideways_by_the_radius_times_the_change() -> None:
    radius = load_robot("zju-60").radius_m
    model, data = _sphere(radius)
    _settle(model, data, 2.0)  # onto its contact
    moves: list[tuple[float, float, float]] = []
    for swing in (0.2, -0.15, 0.25, 0.0):  # the pendulum's angle to the shell (rad)
        y0, roll0 = float(data.qpos[1]), _shell_roll(data)
        data.ctrl[0] = swing
        _settle(model, data, 20.0)
        d_roll, d_y = _shell_roll(data) - roll0, float(data.qpos[1]) - y0
        pendulum = float(data.qpos[7]) + _shell_roll(data)  # its angle to the vertical
        assert pendulum == pytest.approx(0.0, abs=1e-3)  # hanging straight down again: the shell rolled
        assert d_roll == pytest.approx(-(swing - (moves[-1][0] if moves else 0.0)), abs=2e-3)
        moves.append((swing, d_roll, d_y))
    rolled = np.array([m[1] for m in moves])
    shifted = np.array([m[2] for m in moves])
    assert np.abs(rolled).min() > 0.1  # every move a roll change of 6° or more
    # eq. 1: the centre moves by r·Δφ sideways, within the contact's give; the planner's roll φ is the shell's
    # rotation about the heading's axis taken positive rolling to the left (+y), here minus its rotation about x
    planned = np.array([roll_shift(0.0, 0.0, 0.0, radius, -r)[1] for r in rolled])
    np.testing.assert_allclose(shifted, planned, rtol=0.03)
    assert np.all(np.abs(np.array([roll_shift(0.0, 0.0, 0.0, radius, -r)[0] for r in rolled])) < 1e-12)
    assert abs(float(data.qpos[0])) < 1e-6  # and the sphere did not move forwards either
