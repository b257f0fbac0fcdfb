"""The one rule for angles every door applies (docs/contracts.md, "Shared contracts").

Angles are radians. A value outside [−2π, 2π] is taken to be a mistake — degrees given as radians (a yaw of
180 would otherwise plan to −2.21 rad without a word) — and refused naming the field, with ``hint`` saying how
to give degrees at that door (``--degrees`` on the CLI, ``yaw_deg`` or ``"degrees": true`` on the wire).
Reported yaws are wrapped to (−π, π]. Pure Python: the CLI's argument checks import it before numba.
"""

from __future__ import annotations

import math

from planner.errors import InvalidInput

#: the largest |angle| accepted (rad); in degrees, 360
MAX_ANGLE_RAD = 2.0 * math.pi


def check_angle(field: str, value_rad: float, hint: str) -> float:
    """``value_rad`` if it is a finite angle in [−2π, 2π], else :class:`InvalidInput` naming ``field``."""
    if not math.isfinite(value_rad):
        raise InvalidInput(field, f"must be a finite angle, got {value_rad!r}")
    if abs(value_rad) > MAX_ANGLE_RAD + 1e-12:
        raise InvalidInput(field, f"{value_rad:g} rad is outside [−2π, 2π] ({math.degrees(value_rad):.0f}°): "
                                  f"angles are radians; for degrees use {hint}")
    return value_rad


def wrap_angle(a: float) -> float:
    """``a`` wrapped to (−π, π] (the way every reported yaw is)."""
    w = math.atan2(math.sin(a), math.cos(a))
    return math.pi if w == -math.pi else w
