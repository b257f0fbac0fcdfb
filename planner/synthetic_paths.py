"""Synthetic plans in the plan-result format, for tests, demos and the simulators of every wing.

Two ways to build one. :func:`plan_from_rolls` rolls eq. 1 of paper 001 through a roll schedule (every
path exactly rollable, roll ramped at a finite rate); :func:`plan_from_curvatures` chains exact arcs and
straights of given curvature (the curvature steps at segment ends, as a path cut from a geometric
planner would), with each state's roll from the profile's roll model.

Reference paths built by rolling eq. 1 of paper 001 through a roll schedule:

They stand in for planner output in tests and demos: a straight line, an arc at the minimum turning
radius, an S-curve, and the 16.2 m × 8.4 m rectangular track of paper 001's positioning run (§6,
Fig. 7) driven clockwise with rounded corners. A path is a list of segments (length m, roll rad); the
roll ramps to each segment's value at ``ramp_rate`` (rad/s, default half the profile's roll-rate limit)
at the path speed, and the centre moves by eq. 1 (including the sideways r·φ̇ term), so every path is
exactly rollable by the profile. The result is a dict shaped like the plan result JSON (docs/contracts.md):
``states`` [{x, y, yaw, roll, v, t, s, curvature}] at most ``spacing_m`` apart, ``robot``, ``status``...
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from planner.robot import RobotProfile


def _roll_path(
    robot: RobotProfile,
    segments: Sequence[tuple[float, float]],
    start: tuple[float, float, float],
    speed_m_s: float,
    ramp_rate: float,
    step_m: float = 0.002,
) -> np.ndarray:
    """Integrate eq. 1 over arc length; rows (s, x, y, yaw, roll, curvature), one per ``step_m``."""
    x, y, yaw = start
    roll = 0.0
    r = robot.radius_m
    rows = [(0.0, x, y, yaw, roll, float(robot.roll_model.curvature(roll)))]
    s = 0.0
    dphi_max = ramp_rate / speed_m_s * step_m  # roll change per step while ramping (dφ/ds = φ̇ / v)
    for length, target in segments:
        n = max(1, round(length / step_m))
        h = length / n
        for _ in range(n):
            d_roll = float(np.clip(target - roll, -dphi_max, dphi_max)) * h / step_m
            roll_mid = roll + 0.5 * d_roll
            k = float(robot.roll_model.curvature(roll_mid))
            th = yaw + 0.5 * k * h
            x += h * math.cos(th) - r * d_roll * math.sin(th)
            y += h * math.sin(th) + r * d_roll * math.cos(th)
            yaw += k * h
            roll += d_roll
            s += h
            rows.append((s, x, y, yaw, roll, float(robot.roll_model.curvature(roll))))
    return np.array(rows)


def _as_plan(
    robot: RobotProfile, rows: np.ndarray, speed_m_s: float, spacing_m: float, name: str
) -> dict[str, Any]:
    every = max(1, int(spacing_m / (rows[1, 0] - rows[0, 0]) + 1e-9)) if len(rows) > 1 else 1
    keep = list(range(0, len(rows), every))
    if keep[-1] != len(rows) - 1:
        keep.append(len(rows) - 1)
    states = [
        {
            "x": float(r[1]),
            "y": float(r[2]),
            "yaw": float(r[3]),
            "roll": float(r[4]),
            "v": speed_m_s,
            "t": float(r[0] / speed_m_s),
            "s": float(r[0]),
            "curvature": float(r[5]),
        }
        for r in rows[keep]
    ]
    return {
        "status": "exact",
        "error_code": 0,
        "error_msg": "",
        "name": name,
        "length_m": float(rows[-1, 0]),
        "robot": robot.to_json(),
        "states": states,
    }


def plan_from_rolls(
    robot: RobotProfile,
    segments: Sequence[tuple[float, float]],
    start: tuple[float, float, float] = (0.0, 0.0, 0.0),
    speed_m_s: float | None = None,
    spacing_m: float = 0.025,
    ramp_rate: float | None = None,
    name: str = "synthetic",
) -> dict[str, Any]:
    """A plan that rolls ``segments`` [(length m, roll rad), ...] from ``start`` (x, y, yaw) at ``speed_m_s``.

    The roll starts at 0 and ramps to each segment's roll at ``ramp_rate`` rad/s (default half the
    profile's limit), so segments shorter than their ramp never reach their roll.
    """
    v = robot.max_speed_m_s if speed_m_s is None else speed_m_s
    rate = 0.5 * robot.max_roll_rate_rad_s if ramp_rate is None else ramp_rate
    rows = _roll_path(robot, segments, start, v, rate)
    return _as_plan(robot, rows, v, spacing_m, name)


def plan_from_curvatures(
    robot: RobotProfile,
    segments: Sequence[tuple[float, float]],
    speed_m_s: float | None = None,
    spacing_m: float = 0.025,
) -> dict[str, Any]:
    """A plan of ``segments`` [(length m, curvature 1/m), ...] from the origin heading +x: exact arcs and
    straights, constant speed, each state's roll the profile's roll for its curvature."""
    v = robot.max_speed_m_s if speed_m_s is None else speed_m_s
    states: list[dict[str, float]] = []
    x = y = yaw = s = 0.0

    def add(k: float) -> None:
        roll = float(robot.roll_model.roll_for_curvature(k))
        states.append({"x": x, "y": y, "yaw": yaw, "roll": roll, "v": v, "t": s / v, "s": s, "curvature": k})

    add(segments[0][1])
    for length, k in segments:
        n = max(1, math.ceil(length / spacing_m))
        ds = length / n
        for _ in range(n):
            if abs(k) < 1e-12:
                x += ds * math.cos(yaw)
                y += ds * math.sin(yaw)
            else:
                x += (math.sin(yaw + k * ds) - math.sin(yaw)) / k
                y += (math.cos(yaw) - math.cos(yaw + k * ds)) / k
                yaw += k * ds
            s += ds
            add(k)
    return {"status": "exact", "error_code": 0, "error_msg": "", "name": "curvatures", "length_m": s,
            "robot": robot.to_json(), "states": states}


def circle_plan(robot: RobotProfile, radius_m: float = 1.2, turns: float = 1.0) -> dict[str, Any]:
    """A 0.5 m straight run-in, then ``turns`` left circles of ``radius_m`` (curvature steps, no roll ramp)."""
    return plan_from_curvatures(robot, [(0.5, 0.0), (2 * math.pi * radius_m * turns, 1.0 / radius_m)])


def straight_plan(
    robot: RobotProfile, length_m: float = 3.0, start: tuple[float, float, float] = (0.0, 0.0, 0.0)
) -> dict[str, Any]:
    """A straight line of ``length_m`` along the start heading."""
    return plan_from_rolls(robot, [(length_m, 0.0)], start, name="straight")


def arc_plan(
    robot: RobotProfile,
    angle_rad: float = math.pi / 2,
    lead_m: float = 0.5,
    start: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> dict[str, Any]:
    """A lead-in straight, then a left arc at the maximum roll (minimum turning radius) turning ``angle_rad``
    (the ramp-in included), then a short straight."""
    rate = 0.5 * robot.max_roll_rate_rad_s
    ramp_m = robot.max_roll_rad / rate * robot.max_speed_m_s
    k = robot.max_curvature
    hold = max(0.0, angle_rad / k - ramp_m)
    return plan_from_rolls(
        robot, [(lead_m, 0.0), (hold + ramp_m, robot.max_roll_rad), (lead_m, 0.0)], start, name="arc"
    )


def s_curve_plan(robot: RobotProfile, start: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> dict[str, Any]:
    """Left then right at 80 % of the maximum roll, with straights before, between and after."""
    roll = 0.8 * robot.max_roll_rad
    turn_m = (math.pi / 3) / float(robot.roll_model.curvature(roll))
    return plan_from_rolls(
        robot, [(0.5, 0.0), (turn_m, roll), (turn_m, -roll), (0.5, 0.0)], start, name="s-curve"
    )


def track_plan(
    robot: RobotProfile,
    width_m: float = 16.2,
    height_m: float = 8.4,
    corner_radius_m: float = 1.5,
    origin: tuple[float, float] = (0.0, 0.0),
    speed_m_s: float | None = None,
) -> dict[str, Any]:
    """One clockwise lap of paper 001's rectangular track (§6, Fig. 7): 16.2 m × 8.4 m, rounded corners.

    The rectangle's lower-left corner is at ``origin``; the lap starts and ends on the left side just
    above the lower-left corner, heading +y. Corners turn right at the roll of ``corner_radius_m``
    (at least the profile's minimum turning radius), ramping the roll in and out; the straights are
    sized so the lap spans the rectangle and closes on itself (the four identical corners cancel).
    """
    from planner.errors import InvalidInput

    if corner_radius_m < robot.min_turning_radius_m - 1e-9:
        raise InvalidInput(
            "corner_radius_m",
            f"{corner_radius_m} m is tighter than the robot's minimum turning "
            f"radius {robot.min_turning_radius_m:.3f} m",
        )
    v = robot.max_speed_m_s if speed_m_s is None else speed_m_s
    rate = 0.5 * robot.max_roll_rate_rad_s
    roll_c = -float(robot.roll_model.roll_for_curvature(1.0 / corner_radius_m))
    # yaw turned while ramping 0 → roll_c and back, to size the hold so one corner turns exactly −π/2
    ramp = _roll_path(robot, [(abs(roll_c) / rate * v, roll_c)], (0.0, 0.0, 0.0), v, rate)
    ramp_yaw = abs(ramp[-1, 3])
    hold = (math.pi / 2 - 2 * ramp_yaw) / abs(float(robot.roll_model.curvature(roll_c)))
    if hold < 0:
        raise InvalidInput("corner_radius_m", "too tight for the roll ramp")
    corner = [(hold + abs(roll_c) / rate * v, roll_c), (abs(roll_c) / rate * v, 0.0)]
    c = _roll_path(robot, corner, (0.0, 0.0, math.pi / 2), v, rate)
    # the corner in its entry frame (heading +y): forward = +y, to the right = +x
    right, forward = float(c[-1, 1]), float(c[-1, 2])
    a = height_m - right - forward
    b = width_m - right - forward
    if a <= 0 or b <= 0:
        raise InvalidInput("corner_radius_m", "the corners do not fit the track")
    segs: list[tuple[float, float]] = []
    for side in (a, b, a, b):
        segs.extend([(side, 0.0), *corner])
    rows = _roll_path(robot, segs, (origin[0], origin[1] + right, math.pi / 2), v, rate)
    return _as_plan(robot, rows, v, 0.025, "track")
