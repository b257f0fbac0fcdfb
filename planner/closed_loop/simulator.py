"""The simulated sphere: paper 001 eq. 1 integrated with the actuator limits of a robot profile.

The true state is (x, y, θ, φ, v): centre position (m, ``map`` frame), yaw θ (rad, CCW), pendulum roll
φ (rad, > 0 turns left) and wheel speed v (m/s, the shell's rolling speed the encoders see). Eq. 1 of
paper 001 (docs/references.md: the ground truth)::

    ẋ = v_g cos θ − r φ̇ sin θ,   ẏ = v_g sin θ + r φ̇ cos θ,   θ̇ = v_g · κ(φ)

with κ(φ) from the profile's :class:`~planner.robot.RollModel` (tan φ / r for kinematic profiles) and
v_g the ground speed (= v without slip; the slip factor comes from :class:`Disturbances`).

Assumptions (not in the paper; documented in docs/simulation.md): the roll follows its command with a
first-order lag of ``roll_time_constant_s`` whose rate is clipped to ``max_roll_rate_rad_s``, and
``|φ| ≤ max_roll_rad``; the wheel speed reaches its command as fast as ``max_accel_m_s2`` allows and
``|v| ≤ max_speed_m_s``. A control period is integrated with ``substeps`` RK4 steps during which φ and v
change linearly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from planner.kinematics import SphereState
from planner.robot import RobotProfile


@dataclass(frozen=True)
class Disturbances:
    """Seeded disturbances of one simulation run (all zero = the noise-free run).

    slip_scale : ground speed = wheel speed · (1 − slip_scale) (fraction; odometry over-counts distance)
    slip_noise : relative white noise on the ground speed per control step (1 σ, fraction)
    imu_roll_bias_rad, imu_roll_noise_rad : IMU roll error (bias, 1 σ white) — the odometry's yaw drift
    encoder_noise : relative white noise on the encoder distance per control step (1 σ, fraction)
    gnss_noise_m : GNSS position noise (1 σ per axis, m); RTK gives centimetres (paper 001 §6)
    gnss_rate_hz : GNSS fix rate
    gnss_outage_rate_hz, gnss_outage_s : outages start as a Poisson process; each lasts a uniform time
        in [gnss_outage_s[0], gnss_outage_s[1]] (paper 001 §3.1: signals are frequently obstructed)
    gnss_available : False = GNSS-denied (the garage of paper 001 §6): odometry only
    init_xy_m, init_yaw_rad : initial pose error (1 σ): the robot starts off the plan's start while the
        estimator believes it is on it
    """

    slip_scale: float = 0.0
    slip_noise: float = 0.0
    imu_roll_bias_rad: float = 0.0
    imu_roll_noise_rad: float = 0.0
    encoder_noise: float = 0.0
    gnss_noise_m: float = 0.0
    gnss_rate_hz: float = 10.0
    gnss_outage_rate_hz: float = 0.0
    gnss_outage_s: tuple[float, float] = (2.0, 6.0)
    gnss_available: bool = True
    init_xy_m: float = 0.0
    init_yaw_rad: float = 0.0

    @classmethod
    def none(cls) -> Disturbances:
        """No disturbance at all: perfect sensors, exact GNSS at 10 Hz."""
        return cls()

    @classmethod
    def default(cls) -> Disturbances:
        """The default noisy run (all values are assumptions; see docs/simulation.md)."""
        return cls(
            slip_scale=0.03,
            slip_noise=0.05,
            imu_roll_bias_rad=math.radians(0.1),
            imu_roll_noise_rad=math.radians(0.3),
            encoder_noise=0.01,
            gnss_noise_m=0.02,
            gnss_rate_hz=10.0,
            gnss_outage_rate_hz=1.0 / 30.0,
            gnss_outage_s=(2.0, 6.0),
            init_xy_m=0.03,
            init_yaw_rad=math.radians(1.0),
        )

    @classmethod
    def named(cls, name: str) -> Disturbances:
        """``"none"`` or ``"default"``."""
        if name == "none":
            return cls.none()
        if name == "default":
            return cls.default()
        from planner.errors import InvalidInput

        raise InvalidInput("noise", f"must be 'none' or 'default', got {name!r}")


@dataclass(frozen=True)
class StepResult:
    """What one control period produced: the new state and the wheel distance the encoders saw (m)."""

    state: SphereState
    wheel_distance_m: float


class SphereSimulator:
    """Integrates eq. 1 for one robot profile over control periods with a finer internal RK4 step."""

    def __init__(self, robot: RobotProfile, substeps: int = 10) -> None:
        if substeps < 1:
            raise ValueError("substeps must be >= 1")
        self.robot = robot
        self.substeps = substeps

    def _kappa(self, roll: float) -> float:
        model = self.robot.roll_model
        if model.kind == "kinematic":
            return math.tan(roll) / model.radius_m
        return float(model.curvature(roll))

    def step(
        self, state: SphereState, v_cmd: float, roll_cmd: float, dt_s: float, ground_factor: float = 1.0
    ) -> StepResult:
        """Advance ``state`` by ``dt_s`` seconds under the command (wheel speed m/s, roll rad).

        ``ground_factor`` multiplies the wheel speed to give the ground speed (slip; 1 = pure rolling).
        Returns the new state and the wheel distance (m, signed) rolled during the period.
        """
        rob = self.robot
        v_cmd = float(np.clip(v_cmd, -rob.max_speed_m_s, rob.max_speed_m_s))
        roll_cmd = float(np.clip(roll_cmd, -rob.max_roll_rad, rob.max_roll_rad))
        h = dt_s / self.substeps
        x, y, yaw, roll, v = state.x, state.y, state.yaw, state.roll, state.v
        wheel = 0.0
        r = rob.radius_m
        decay = math.exp(-h / rob.roll_time_constant_s)
        for _ in range(self.substeps):
            # actuators: first-order roll with a rate limit, speed with an acceleration limit
            roll_target = roll_cmd + (roll - roll_cmd) * decay
            max_dr = rob.max_roll_rate_rad_s * h
            roll1 = roll + float(np.clip(roll_target - roll, -max_dr, max_dr))
            roll1 = float(np.clip(roll1, -rob.max_roll_rad, rob.max_roll_rad))
            max_dv = rob.max_accel_m_s2 * h
            v1 = v + float(np.clip(v_cmd - v, -max_dv, max_dv))
            roll_rate = (roll1 - roll) / h

            def rhs(
                f: float,
                th: float,
                v0: float = v,
                v1_: float = v1,
                p0: float = roll,
                p1: float = roll1,
                rate: float = roll_rate,
            ) -> tuple[float, float, float]:
                vg = (v0 + f * (v1_ - v0)) * ground_factor
                k = self._kappa(p0 + f * (p1 - p0))
                return (
                    vg * math.cos(th) - r * rate * math.sin(th),
                    vg * math.sin(th) + r * rate * math.cos(th),
                    vg * k,
                )

            k1 = rhs(0.0, yaw)
            k2 = rhs(0.5, yaw + 0.5 * h * k1[2])
            k3 = rhs(0.5, yaw + 0.5 * h * k2[2])
            k4 = rhs(1.0, yaw + h * k3[2])
            x += h / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            y += h / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            yaw += h / 6.0 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
            wheel += 0.5 * (v + v1) * h
            roll, v = roll1, v1
        return StepResult(replace(state, x=x, y=y, yaw=yaw, roll=roll, v=v), wheel)
