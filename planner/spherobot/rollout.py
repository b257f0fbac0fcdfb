"""Rolling a candidate manoeuvre through SO(3): the proof every paper 004 plan must pass before it is returned.

A manoeuvre from either planner (§3 spherical triangles, §4 straight rolls and circles) is rolled exactly,
without slipping (§2, the eq. 1–4 model, via :mod:`planner.spherobot.rolling`), and sampled at most
``SAMPLE_SPACING``·R of rolling apart; :func:`goal_errors` measures how far the rolled end state is from
the goal: the centre's position, P's angle from the top and, for a complete reconfiguration, the heading.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.kinematics import wrap
from planner.spherobot.manoeuvre import Manoeuvre
from planner.spherobot.rolling import Quat, sample_segment, tilt_from_quat

SAMPLE_SPACING = 0.02  # samples at most this many radii of rolling apart


@dataclass(frozen=True)
class RolledManoeuvre:
    """A manoeuvre rolled through SO(3): samples (N,) t, x, y and (N, 4) quaternions; per-segment starts."""

    manoeuvre: Manoeuvre
    t: np.ndarray
    xy: np.ndarray
    quat: np.ndarray
    segment_quat: tuple[Quat, ...]
    segment_t0: tuple[float, ...]

    @property
    def final_quat(self) -> Quat:
        return tuple(float(v) for v in self.quat[-1])  # type: ignore[return-value]


def roll_manoeuvre(
    m: Manoeuvre, start: tuple[float, float], q0: Quat, radius_m: float, speed_m_s: float
) -> RolledManoeuvre:
    """Roll ``m`` exactly and sample it at most ``SAMPLE_SPACING·R`` of rolling apart."""
    ts: list[np.ndarray] = [np.zeros(1)]
    xys: list[np.ndarray] = [np.array([start], dtype=float)]
    qs: list[np.ndarray] = [np.array([q0], dtype=float)]
    seg_q: list[Quat] = []
    seg_t0: list[float] = []
    q, t = q0, 0.0
    step = SAMPLE_SPACING * radius_m
    for seg in m.segments:
        seg_q.append(q)
        seg_t0.append(t)
        if seg.length_m <= 0.0:
            continue
        n = max(1, math.ceil(seg.length_m / step - 1e-9))
        s = np.linspace(0.0, seg.length_m, n + 1)[1:]
        quats = sample_segment(q, seg, radius_m, s)
        x, y = seg.point_at(s)
        ts.append(t + s / speed_m_s)
        xys.append(np.column_stack([x, y]))
        qs.append(quats)
        q = tuple(float(v) for v in quats[-1])  # type: ignore[assignment]
        t += seg.length_m / speed_m_s
    return RolledManoeuvre(
        m, np.concatenate(ts), np.concatenate(xys), np.concatenate(qs), tuple(seg_q), tuple(seg_t0)
    )


def goal_errors(
    xy: Sequence[float], q: Quat, goal: tuple[float, float], goal_heading: float | None
) -> tuple[float, float, float | None]:
    """(position error m, P's angle from the top rad, heading error rad or None) of a final state."""
    theta, _, spin = tilt_from_quat(q)
    head_err = None if goal_heading is None else abs(wrap(spin - goal_heading))
    return math.hypot(xy[0] - goal[0], xy[1] - goal[1]), theta, head_err
