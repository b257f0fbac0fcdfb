"""A Spherobot reconfiguration problem (paper 004, docs/references.md), as the planners take it.

The start state is the paper's: the centre's position, the tilt (θ, α) of the camera point P from the top
(Fig. 2; the orientation Rot((−sin α, cos α, 0), θ)·Rz(spin) of the eq. 1–4 model) and a spin about P;
the goal is a position with P on top and, for a complete reconfiguration (§3.2 spherical triangles,
§4.3 arcs), a heading, or for a partial one (§4.2) optionally the direction α_f of the arc method's last
roll. :class:`ReconfigureRequest` reads the JSON request, checks every field and fills the sphere's
radius and rolling rate from the ``spherobot`` profile.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from planner.angles import check_angle
from planner.errors import InvalidInput
from planner.robot import load_robot
from planner.spherobot.rolling import Quat, quat_from_tilt

METHODS = ("arc", "triangle")
ROBOT = "spherobot"
#: largest sphere a request may roll (m): a rolled result is sampled per radius, so absurd radii break the numbers
MAX_RADIUS_M = 100.0
#: farthest goal, in sphere radii from the start (paper 004's examples are a few radii; samples grow with it)
MAX_RADII = 200


@dataclass(frozen=True)
class ReconfigureRequest:
    """A reconfiguration problem (SI units, radians), checked when it is made.

    ``start_tilt`` is (θ, α) of paper 004 Fig. 2: P = (sin θ cos α, sin θ sin α, cos θ), θ ∈ [0, π]; the
    start orientation is Rot((−sin α, cos α, 0), θ)·Rz(start_spin). Without ``goal_heading`` (azimuth of
    body +x with P on top) it is a partial reconfiguration; ``alpha_final`` (arc method only) fixes the
    direction of the last roll. ``radius_m`` and ``roll_rate_rad_s`` default to the ``spherobot`` profile.
    """

    method: str
    start: tuple[float, float]
    goal: tuple[float, float]
    start_tilt: tuple[float, float] = (0.0, 0.0)
    start_spin: float = 0.0
    goal_heading: float | None = None
    alpha_final: float | None = None
    radius_m: float | None = None
    roll_rate_rad_s: float | None = None
    map: str | None = None
    allow_unknown: bool = False

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ReconfigureRequest:
        """Read a JSON request (the CLI's, HTTP's and Zenoh's): angles are in degrees when ``degrees`` is
        true; unknown keys and wrong types raise InvalidInput naming the field."""
        known = {f for f in cls.__dataclass_fields__} | {"degrees"}
        for key in data:
            if key not in known:
                raise InvalidInput(key, f"unknown field; expected some of {sorted(known)}")
        deg = data.get("degrees", False)
        if not isinstance(deg, bool):
            raise InvalidInput("degrees", "must be true or false")
        scale = math.pi / 180.0 if deg else 1.0
        method = data.get("method", "arc")
        if method not in METHODS:
            raise InvalidInput("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
        if "start" not in data:
            raise InvalidInput("start", "is required")
        if "goal" not in data:
            raise InvalidInput("goal", "is required")
        tilt = _pair(data.get("start_tilt", (0.0, 0.0)), "start_tilt")
        map_path = data.get("map")
        if map_path is not None and not isinstance(map_path, str):
            raise InvalidInput("map", "must be a path to a map YAML")
        allow_unknown = data.get("allow_unknown", False)
        if not isinstance(allow_unknown, bool):
            raise InvalidInput("allow_unknown", "must be true or false")
        return cls(
            method=method,
            start=_pair(data["start"], "start"),
            goal=_pair(data["goal"], "goal"),
            start_tilt=(tilt[0] * scale, tilt[1] * scale),
            start_spin=_number(data.get("start_spin", 0.0), "start_spin") * scale,
            goal_heading=_optional(data.get("goal_heading"), "goal_heading", scale),
            alpha_final=_optional(data.get("alpha_final"), "alpha_final", scale),
            radius_m=_optional(data.get("radius_m"), "radius_m", 1.0),
            roll_rate_rad_s=_optional(data.get("roll_rate_rad_s"), "roll_rate_rad_s", 1.0),
            map=map_path,
            allow_unknown=allow_unknown,
        )

    def __post_init__(self) -> None:
        """Check every field and fill ``radius_m`` and ``roll_rate_rad_s`` from the profile when not given,
        so a request that exists is one the planners can take; raises InvalidInput naming the field."""
        if self.method not in METHODS:
            raise InvalidInput("method", f"must be one of {', '.join(METHODS)}, got {self.method!r}")
        for name in ("start", "goal", "start_tilt"):
            for v in getattr(self, name):
                _number(v, name)
        _number(self.start_spin, "start_spin")
        theta = self.start_tilt[0]
        if not 0.0 <= theta <= math.pi:
            raise InvalidInput("start_tilt", f"θ must be in [0, π] rad (0..180°), got {theta!r}")
        for name in ("goal_heading", "alpha_final"):
            v = getattr(self, name)
            if v is not None:
                _number(v, name)
        # the one angle rule of every door (planner.angles): radians in [−2π, 2π]
        hint = "--degrees (CLI) or \"degrees\": true (HTTP, Zenoh)"
        check_angle("start_tilt", self.start_tilt[1], hint)
        for name in ("start_spin", "goal_heading", "alpha_final"):
            if getattr(self, name) is not None:
                check_angle(name, getattr(self, name), hint)
        if self.alpha_final is not None and self.method != "arc":
            raise InvalidInput("alpha_final", "only the arc method has a final roll direction")
        if self.alpha_final is not None and self.goal_heading is not None:
            raise InvalidInput("alpha_final", "cannot be combined with goal_heading (the heading fixes α_f)")
        if self.radius_m is None or self.roll_rate_rad_s is None:
            profile = load_robot(ROBOT)
            if self.radius_m is None:
                object.__setattr__(self, "radius_m", profile.radius_m)
            if self.roll_rate_rad_s is None:
                rate = float(profile.extra.get("spherobot", {}).get("roll_rate_rad_s", 1.0))
                object.__setattr__(self, "roll_rate_rad_s", rate)
        for name in ("radius_m", "roll_rate_rad_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise InvalidInput(name, f"must be a finite number > 0, got {v!r}")
        radius = float(self.radius_m or 0.0)  # filled and checked > 0 above
        if radius > MAX_RADIUS_M:
            raise InvalidInput("radius_m", f"must be at most {MAX_RADIUS_M:g} m, got {radius:g}")
        distance = math.dist(self.start, self.goal)
        if distance > MAX_RADII * radius:
            raise InvalidInput("goal", f"is {distance:.3g} m from the start; a reconfiguration rolls at most "
                                       f"{MAX_RADII} sphere radii ({MAX_RADII * radius:.3g} m)")

    @property
    def start_quat(self) -> Quat:
        return quat_from_tilt(self.start_tilt[0], self.start_tilt[1], self.start_spin)


def _number(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InvalidInput(field, f"must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InvalidInput(field, f"must be finite, got {value!r}")
    return float(value)


def _optional(value: Any, field: str, scale: float) -> float | None:
    return None if value is None else _number(value, field) * scale


def _pair(value: Any, field: str) -> tuple[float, float]:
    if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != 2:
        raise InvalidInput(field, f"must be two numbers, got {value!r}")
    return _number(value[0], field), _number(value[1], field)
