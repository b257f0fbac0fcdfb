"""Exact motion of the rolling sphere over one planning step (paper 001 eq. 1, corrected eq. 14a–c).

Paper 001 eq. 1 (the ground truth, docs/references.md):

    ẋ = v cos θ − r φ̇ sin θ,   ẏ = v sin θ + r φ̇ cos θ,   θ̇ = v tan φ / r

A Hybrid-A* child holds a constant roll φc. Changing the roll from φp to φc rolls the shell sideways:
integrating the φ̇ terms with θ fixed shifts the centre by r·Δφ along the left normal
(−sin θ, cos θ) (the printed eq. 14a–b uses sin/cos φp there: a typo). Holding φc while rolling a
signed arc length s (negative when reversing) turns the heading by κ(φc)·s and moves the centre along a
circle of radius 1/κ (the printed factor v·Δt in front of (sin θc − sin θp) is only right in the
straight limit; the correct factor is the turning radius 1/κ = r / tan φc).

``κ(φ)`` comes from the robot's :class:`~planner.robot.RollModel` (tan φ / r for the kinematic model).
All functions are numba-compiled so the search can call them in its inner loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from planner.jit import njit_leaf


@dataclass(frozen=True)
class SphereState:
    """The sphere's kinematic state, as simulators and controllers exchange it: position (m), yaw (rad),
    roll (rad) and wheel speed (m/s). The kinematic simulator's truth and the dynamic plant's snapshot."""

    x: float
    y: float
    yaw: float
    roll: float = 0.0
    v: float = 0.0

STRAIGHT_EPS = 1e-9


@njit_leaf
def roll_shift(x: float, y: float, yaw: float, radius_m: float, d_roll: float) -> tuple[float, float]:
    """Centre after changing roll by ``d_roll`` (rad) at heading ``yaw``: eq. 1 with v = 0."""
    return roll_shift_cs(x, y, math.cos(yaw), math.sin(yaw), radius_m, d_roll)


@njit_leaf
def roll_shift_cs(x: float, y: float, c: float, s: float, radius_m: float, d_roll: float) -> tuple[float, float]:
    """:func:`roll_shift` given the heading's cosine ``c`` and sine ``s`` (the search has them already)."""
    return x - radius_m * d_roll * s, y + radius_m * d_roll * c


@njit_leaf
def arc_step(x: float, y: float, yaw: float, curvature: float, s: float) -> tuple[float, float, float]:
    """Pose after rolling signed arc length ``s`` (m) at constant ``curvature`` (1/m): eq. 1 with φ̇ = 0."""
    if abs(curvature) < STRAIGHT_EPS:
        return x + s * math.cos(yaw), y + s * math.sin(yaw), yaw
    yaw2 = yaw + curvature * s
    return (
        x + (math.sin(yaw2) - math.sin(yaw)) / curvature,
        y - (math.cos(yaw2) - math.cos(yaw)) / curvature,
        yaw2,
    )


@njit_leaf
def child_pose(
    x: float, y: float, yaw: float, roll_p: float, roll_c: float, curvature_c: float, radius_m: float, s: float
) -> tuple[float, float, float]:
    """Hybrid-A* child of eq. 14 (corrected): roll change φp→φc, then an arc of length ``s`` at φc."""
    x1, y1 = roll_shift(x, y, yaw, radius_m, roll_c - roll_p)
    return arc_step(x1, y1, yaw, curvature_c, s)


@njit(cache=True)
def motion_knots(x: float, y: float, yaw: float, roll: float, motions: np.ndarray, radius_m: float) -> np.ndarray:
    """Pose (x, y, yaw, roll) and distance travelled at the start and after every motion: (n+1, 5) rows.

    ``motions`` rows are (held roll, curvature, signed arc length) from (x, y, yaw) at ``roll``; the distance
    counts each arc's length and each roll change's sideways shift. (The planner calls this on every
    candidate path of its smoother, a thousand times per plan: it ran in Python before.)
    """
    out = np.empty((motions.shape[0] + 1, 5))
    dist = 0.0
    out[0, 0], out[0, 1], out[0, 2], out[0, 3], out[0, 4] = x, y, yaw, roll, dist
    for k in range(motions.shape[0]):
        held, curv, s = motions[k, 0], motions[k, 1], motions[k, 2]
        x, y, yaw = child_pose(x, y, yaw, roll, held, curv, radius_m, s)
        dist += abs(s) + radius_m * abs(held - roll)
        roll = held
        out[k + 1, 0], out[k + 1, 1], out[k + 1, 2], out[k + 1, 3], out[k + 1, 4] = x, y, yaw, roll, dist
    return out


@njit(cache=True)
def densify_motions(start: np.ndarray, motions: np.ndarray, radius_m: float, spacing_m: float) -> np.ndarray:
    """Dense poses along a chain of motions, consecutive rows at most ``spacing_m`` apart.

    ``start`` is (x, y, yaw) with roll 0; ``motions`` rows are (held roll, curvature, signed arc length):
    each rolls sideways to the held roll (eq. 1, v = 0) then along the arc. Returns (n, 5) rows
    (x, y, yaw, roll, direction) with direction +1 forward, −1 reverse (0 for the start row).
    """
    total = 1
    roll = 0.0
    for k in range(motions.shape[0]):
        total += math.ceil(abs(radius_m * (motions[k, 0] - roll)) / spacing_m)
        total += math.ceil(abs(motions[k, 2]) / spacing_m)
        roll = motions[k, 0]
    out = np.empty((total, 5))
    x, y, yaw, roll = start[0], start[1], start[2], 0.0
    out[0, 0], out[0, 1], out[0, 2], out[0, 3], out[0, 4] = x, y, yaw, 0.0, 0.0
    n = 1
    for k in range(motions.shape[0]):
        held, curv, s = motions[k, 0], motions[k, 1], motions[k, 2]
        direction = 1.0 if s >= 0 else -1.0
        d_roll = held - roll
        m = math.ceil(abs(radius_m * d_roll) / spacing_m)
        for i in range(1, m + 1):
            xs, ys = roll_shift(x, y, yaw, radius_m, d_roll * i / m)
            out[n, 0], out[n, 1], out[n, 2], out[n, 3], out[n, 4] = xs, ys, yaw, roll + d_roll * i / m, direction
            n += 1
        x, y = roll_shift(x, y, yaw, radius_m, d_roll)
        roll = held
        m = math.ceil(abs(s) / spacing_m)
        x0, y0, yaw0 = x, y, yaw
        for i in range(1, m + 1):
            x, y, yaw = arc_step(x0, y0, yaw0, curv, s * i / m)
            out[n, 0], out[n, 1], out[n, 2], out[n, 3], out[n, 4] = x, y, yaw, roll, direction
            n += 1
    return out[:n]


@njit_leaf
def wrap(a: float) -> float:
    """A scalar angle wrapped to (−π, π] (compiled: usable from the search loop and from Python). An angle in the
    range is returned as it is (the search wraps every child's heading, nearly all in range already: a sine, a
    cosine and an atan2 each were a fifth of a plan's CPU samples; they also moved one angle in 25 by an ulp)."""
    if -math.pi < a <= math.pi:
        return a
    w = math.atan2(math.sin(a), math.cos(a))
    return math.pi if w == -math.pi else w


def subdivide(motions: list[tuple[float, float, float]], step: float) -> list[tuple[float, float, float]]:
    """Split motions (held roll, curvature, signed length) longer than ``step`` into equal pieces: the same path,
    more knots to shortcut from (:func:`subdivide_rows` on a list)."""
    rows = subdivide_rows(np.array(motions, float).reshape(-1, 3), step)
    return [(h, c, s) for h, c, s in rows.tolist()]


@njit(cache=True)
def subdivide_rows(motions: np.ndarray, step: float) -> np.ndarray:
    """:func:`subdivide` on rows (n, 3), compiled (the smoother's later passes call it from compiled code)."""
    parts = np.empty(motions.shape[0], dtype=np.int64)
    total = 0
    for k in range(motions.shape[0]):
        parts[k] = max(1, math.ceil(abs(motions[k, 2]) / step - 1e-9))
        total += parts[k]
    out = np.empty((total, 3))
    n = 0
    for k in range(motions.shape[0]):
        for _ in range(parts[k]):
            out[n, 0] = motions[k, 0]
            out[n, 1] = motions[k, 1]
            out[n, 2] = motions[k, 2] / parts[k]
            n += 1
    return out
