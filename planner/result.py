"""The plan result: the sphere's states along the path and the JSON every interface returns (docs/contracts.md).

``states`` rows carry x, y, yaw, roll (rad), v (commanded forward speed, m/s; 0 while the sphere only
rolls sideways to change its roll), t (s), s (distance travelled by the centre, m, sideways shifts
included) and curvature (dyaw/ds of the held roll, 1/m, sign flipped when reversing).
``path`` mirrors ``nav_msgs/Path`` in the ``map`` frame (orientation = yaw only).
``min_clearance_m`` is the smallest exact distance from a footprint circle to a blocked cell, minus the
circle radius, along the path (capped at 1 m: open space reads 1.0).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.robot import RobotProfile

STATE_FIELDS = ("x", "y", "yaw", "roll", "v", "t", "s", "curvature")


def build_states(poses: np.ndarray, robot: RobotProfile) -> np.ndarray:
    """From dense poses (n, 5: x, y, yaw, roll, direction) to states (n, 8) in ``STATE_FIELDS`` order; yaws are
    wrapped to (−π, π], as every reported yaw is (docs/contracts.md)."""
    n = len(poses)
    out = np.zeros((n, 8))
    out[:, :4] = poses[:, :4]
    yaw = np.arctan2(np.sin(poses[:, 2]), np.cos(poses[:, 2]))
    out[:, 2] = np.where(yaw == -np.pi, np.pi, yaw)
    if n == 0:
        return out
    d = np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1]))
    d_roll = np.abs(np.diff(poses[:, 3]))
    shifting = d_roll > 1e-12
    speed = robot.max_speed_m_s
    dt = np.where(shifting, d_roll / robot.max_roll_rate_rad_s, d / speed)
    out[1:, 5] = np.cumsum(dt)
    out[1:, 6] = np.cumsum(d)
    direction = poses[:, 4]
    v = direction * speed
    v[1:][shifting] = 0.0
    v[0] = 0.0
    out[:, 4] = v
    kappa = np.asarray(robot.roll_model.curvature(poses[:, 3]), dtype=float)
    out[:, 7] = kappa * np.where(direction < 0, -1.0, 1.0)
    return out


def nav_path(states: np.ndarray, frame_id: str = "map") -> dict[str, Any]:
    """``nav_msgs/Path`` mirror of the states."""
    poses = []
    for x, y, yaw in states[:, :3]:
        poses.append({
            "header": {"frame_id": frame_id},
            "pose": {
                "position": {"x": float(x), "y": float(y), "z": 0.0},
                "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
            },
        })
    return {"header": {"frame_id": frame_id}, "poses": poses}


@dataclass
class PlanResult:
    """A successful plan. ``states`` is (n, 8) in ``STATE_FIELDS`` order."""

    status: str
    error_code: int
    error_msg: str
    planning_time_s: float
    expansions: int
    robot: RobotProfile
    map_name: str
    start: tuple[float, float, float]
    goal: tuple[float, float, float]
    states: np.ndarray
    min_clearance_m: float
    analytic_segments: int = 0
    extra: dict[str, Any] = field(default_factory=dict)

    def say_which_search(self, reversing: bool) -> None:
        """Record in ``extra`` which search produced the path — ``search``: ``"reversing"`` (the search that may
        roll backwards), ``"forward-only"`` (reversing not allowed) or ``"forward-alternative"`` (the forward-only
        search run beside a reversing one, whose path was kept) — and how much of it rolls backwards
        (``reverse_states``, ``reverse_length_m``), so a plan that reverses is never passed off silently."""
        states = self.states
        backwards = states[:, 4] < 0
        steps = np.hypot(np.diff(states[:, 0]), np.diff(states[:, 1])) if len(states) > 1 else np.zeros(0)
        self.extra["search"] = ("forward-alternative" if self.extra.get("forward_alternative")
                                else "reversing" if reversing else "forward-only")
        self.extra["reverse_states"] = int(backwards.sum())
        self.extra["reverse_length_m"] = float(steps[backwards[1:]].sum()) if len(steps) else 0.0

    @property
    def length_m(self) -> float:
        return float(self.states[-1, 6]) if len(self.states) else 0.0

    @property
    def duration_s(self) -> float:
        return float(self.states[-1, 5]) if len(self.states) else 0.0

    def to_json(self) -> dict[str, Any]:
        return {
            "status": self.status,
            "error_code": self.error_code,
            "error_msg": self.error_msg,
            "planning_time_s": round(self.planning_time_s, 6),
            "length_m": self.length_m,
            "duration_s": self.duration_s,
            "expansions": self.expansions,
            "min_clearance_m": self.min_clearance_m,
            "analytic_expansion_segments": self.analytic_segments,
            "map": self.map_name,
            "start": {"x": self.start[0], "y": self.start[1], "yaw": self.start[2]},
            "goal": {"x": self.goal[0], "y": self.goal[1], "yaw": self.goal[2]},
            "robot": self.robot.to_json(),
            "states": [dict(zip(STATE_FIELDS, map(float, row), strict=True)) for row in self.states],
            "path": nav_path(self.states),
            **self.extra,
        }


def failure_json(code: int, msg: str, robot: RobotProfile | None, planning_time_s: float = 0.0,
                 expansions: int = 0) -> dict[str, Any]:
    """The result JSON of a failed plan (status ``failed``, the Nav2 code and a sentence, the time spent and
    the expansions done before failing)."""
    return {
        "status": "failed",
        "error_code": code,
        "error_msg": msg,
        "planning_time_s": round(planning_time_s, 6),
        "length_m": 0.0,
        "expansions": expansions,
        "robot": robot.to_json() if robot else None,
        "states": [],
        "path": {"header": {"frame_id": "map"}, "poses": []},
    }



def state_column(states: Sequence[Any], key: str, required: bool, where: str = "path.states") -> np.ndarray | None:
    """One field of a plan JSON's ``states`` as a float array, validated with field-named errors.

    Returns None when an optional ``key`` is missing from any state; raises
    :class:`~planner.errors.InvalidInput` (``path.states[i].key``) for a missing required value, a
    non-object state or a value that is not a finite number.
    """
    values = []
    for i, st in enumerate(states):
        if not isinstance(st, Mapping):
            raise InvalidInput(f"{where}[{i}]", "must be an object")
        if key not in st or st[key] is None:
            if required:
                raise InvalidInput(f"{where}[{i}].{key}", "is required")
            return None
        v = st[key]
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(float(v)):
            raise InvalidInput(f"{where}[{i}].{key}", f"must be a finite number, got {v!r}")
        values.append(float(v))
    return np.asarray(values)
