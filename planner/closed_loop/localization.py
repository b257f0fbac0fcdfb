"""Localisation of the sphere: wheel odometry (paper 001 eq. 2) and its Kalman fusion with GNSS (eq. 3).

Wheel odometry is eq. 1 written as a recursion over one sensor period, fed by the encoders (rolled wheel
distance Δs) and the IMU roll φ::

    x_k = x_{k−1} + Δs cos θ̄ − r Δφ sin θ̄
    y_k = y_{k−1} + Δs sin θ̄ + r Δφ cos θ̄          θ̄ = θ_{k−1} + Δθ/2 (midpoint heading)
    θ_k = θ_{k−1} + Δs κ(φ̄)                         φ̄ = (φ_{k−1} + φ_k)/2

Eq. 2 as printed writes v and φ̇ where the per-period increments v·Δt and Δφ belong, and uses θ_{k−1};
the midpoint heading is the second-order version of the same recursion (the tests check it against
integrating eq. 1).

The fusion filter is eq. 3: prediction x̂⁻ = f(x̂, u) with the odometry increment as input, P⁻ = A P Aᵀ +
Q; GNSS position z is the observation (H = [I₂ 0]) with gain K = P⁻Hᵀ(HP⁻Hᵀ + R)⁻¹. Paper 001 Table 2
says A = I; with A = I the yaw never correlates with position, so GNSS could never correct the
odometry's yaw drift. We use A = ∂f/∂x (an extended Kalman filter; A → I as Δs, Δφ → 0), which is what
lets the fused estimate remove the yaw drift the paper reports removing. Without GNSS fixes the filter
only predicts, i.e. it degrades to wheel odometry (paper 001 §3.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.robot import RobotProfile


@dataclass(frozen=True)
class OdometryIncrement:
    """One sensor period: encoder distance (m, signed) and the IMU roll (rad) at its start and end."""

    wheel_distance_m: float
    roll_start_rad: float
    roll_end_rad: float


@dataclass(frozen=True)
class FilterParams:
    """Process and observation noise of the fusion filter (assumptions, docs/simulation.md).

    pos_per_m : position process noise per metre rolled (1 σ, m/m) — slip and encoder error
    yaw_per_m : yaw process noise per metre rolled (1 σ, rad/m) — IMU roll bias through κ(φ)
    pos_floor_m, yaw_floor_rad : process noise added every period (1 σ)
    gnss_sigma_m : GNSS observation noise (1 σ per axis, m)
    init_pos_m, init_yaw_rad : initial uncertainty (1 σ)
    """

    pos_per_m: float = 0.08
    yaw_per_m: float = 0.02
    pos_floor_m: float = 1e-4
    yaw_floor_rad: float = 1e-4
    gnss_sigma_m: float = 0.02
    init_pos_m: float = 0.05
    init_yaw_rad: float = math.radians(2.0)


def odometry_step(
    pose: np.ndarray, inc: OdometryIncrement, robot: RobotProfile
) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 2 over one period: the next pose (3,) = (x, y, θ) and the Jacobian A = ∂f/∂(x, y, θ) (3, 3)."""
    ds = inc.wheel_distance_m
    d_roll = inc.roll_end_rad - inc.roll_start_rad
    roll_mid = 0.5 * (inc.roll_start_rad + inc.roll_end_rad)
    d_yaw = ds * float(robot.roll_model.curvature(roll_mid))
    r = robot.radius_m
    th = pose[2] + 0.5 * d_yaw
    c, s = math.cos(th), math.sin(th)
    new = np.array([pose[0] + ds * c - r * d_roll * s, pose[1] + ds * s + r * d_roll * c, pose[2] + d_yaw])
    jac = np.eye(3)
    jac[0, 2] = -ds * s - r * d_roll * c
    jac[1, 2] = ds * c - r * d_roll * s
    return new, jac


class WheelOdometry:
    """Dead reckoning by eq. 2 alone (what the robot has in a GNSS-denied place)."""

    def __init__(self, robot: RobotProfile, pose: tuple[float, float, float]) -> None:
        self.robot = robot
        self.pose = np.array(pose, dtype=float)

    def update(self, inc: OdometryIncrement) -> np.ndarray:
        self.pose, _ = odometry_step(self.pose, inc, self.robot)
        return self.pose


class FusionFilter:
    """Kalman filter of eq. 3 over (x, y, θ): odometry predicts, GNSS position corrects."""

    _H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

    def __init__(
        self, robot: RobotProfile, pose: tuple[float, float, float], params: FilterParams | None = None
    ) -> None:
        self.robot = robot
        self.params = params or FilterParams()
        p = self.params
        self.pose = np.array(pose, dtype=float)
        self.cov = np.diag([p.init_pos_m**2, p.init_pos_m**2, p.init_yaw_rad**2])

    def predict(self, inc: OdometryIncrement) -> np.ndarray:
        """x̂⁻ = f(x̂, u), P⁻ = A P Aᵀ + Q (eq. 3, first two lines)."""
        p = self.params
        self.pose, a = odometry_step(self.pose, inc, self.robot)
        ds = abs(inc.wheel_distance_m)
        q_pos = (p.pos_per_m * ds) ** 2 + p.pos_floor_m**2
        q_yaw = (p.yaw_per_m * ds) ** 2 + p.yaw_floor_rad**2
        self.cov = a @ self.cov @ a.T + np.diag([q_pos, q_pos, q_yaw])
        return self.pose

    def correct(self, z_xy: tuple[float, float]) -> np.ndarray:
        """x̂ = x̂⁻ + K (z − H x̂⁻), K = P⁻Hᵀ(HP⁻Hᵀ + R)⁻¹, P = (I − KH)P⁻ (eq. 3, last three lines)."""
        h = self._H
        r = np.eye(2) * self.params.gnss_sigma_m**2
        s = h @ self.cov @ h.T + r
        k = self.cov @ h.T @ np.linalg.inv(s)
        self.pose = self.pose + k @ (np.asarray(z_xy, dtype=float) - h @ self.pose)
        self.cov = (np.eye(3) - k @ h) @ self.cov
        self.cov = 0.5 * (self.cov + self.cov.T)
        return self.pose
