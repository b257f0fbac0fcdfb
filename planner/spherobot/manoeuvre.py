"""A reconfiguration manoeuvre: the ground segments one planner proposes, before it is rolled and checked.

Both Spherobot planners (paper 004 §3 spherical triangles, §4 straight rolls and circles) return their
candidates as :class:`Manoeuvre` values; ``planner.spherobot.reconfigure`` rolls them through the SO(3) simulator,
samples them and checks them against a map.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from planner.spherobot.rolling import GroundSegment


@dataclass(frozen=True)
class Manoeuvre:
    """One candidate manoeuvre.

    ``segments`` are travelled in order by the sphere's centre (metres, radians); ``steps`` gives each
    segment's role in the paper's algorithm (same length as ``segments``). ``info`` holds the method's own
    outputs (e.g. ``theta_prime_rad``) that go into the result JSON verbatim.
    """

    method: str
    variant: str
    segments: tuple[GroundSegment, ...]
    steps: tuple[str, ...]
    info: Mapping[str, Any] = field(default_factory=dict)

    @property
    def length_m(self) -> float:
        return sum(seg.length_m for seg in self.segments)
