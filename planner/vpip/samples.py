"""Synthetic plans in the planner's result format, for tests and demos of the VPIP schedule.

Each plan is a dict with ``status``, ``robot`` (profile JSON) and ``states``
[{x, y, yaw, roll, v, t, s, curvature}] spaced ``spacing_m`` (≤ 5 cm, docs/contracts.md) at constant speed;
``roll`` is the profile's roll for the state's curvature. Built from arcs and straights.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from planner.robot import RobotProfile


def plan_from_segments(
    profile: RobotProfile,
    segments: Sequence[tuple[float, float]],
    speed_m_s: float | None = None,
    spacing_m: float = 0.025,
) -> dict[str, Any]:
    """Plan made of ``(length_m, curvature_1_m)`` segments, starting at the origin heading +x."""
    v = profile.max_speed_m_s if speed_m_s is None else speed_m_s
    states: list[dict[str, float]] = []
    x = y = yaw = s = 0.0

    def add(k: float) -> None:
        roll = float(profile.roll_model.roll_for_curvature(k))
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
    return {
        "status": "exact",
        "error_code": 0,
        "length_m": s,
        "robot": profile.to_json(),
        "states": states,
    }


def straight_plan(profile: RobotProfile, length_m: float = 3.0) -> dict[str, Any]:
    return plan_from_segments(profile, [(length_m, 0.0)])


def circle_plan(profile: RobotProfile, radius_m: float = 1.2, turns: float = 1.0) -> dict[str, Any]:
    """A left circle (after a 0.5 m straight run-in)."""
    return plan_from_segments(profile, [(0.5, 0.0), (2 * math.pi * radius_m * turns, 1.0 / radius_m)])


def s_curve_plan(profile: RobotProfile, radius_m: float = 1.5) -> dict[str, Any]:
    """Straight, quarter circle left, quarter circle right, straight."""
    q = 0.5 * math.pi * radius_m
    return plan_from_segments(profile, [(0.5, 0.0), (q, 1.0 / radius_m), (q, -1.0 / radius_m), (0.5, 0.0)])
