"""Reeds–Shepp analytic expansions for reversing spheres (paper 001 §4.1's analytic expansion, with reverse).

OMPL's ``ReedsSheppStateSpace`` gives the shortest car path with cusps between two poses at a turning radius
ρ; its Python bindings expose only ``distance`` and ``interpolate``. The path's *word* — its turning
segments (left, straight, right) and their directions — is read off densely interpolated states; then
the segments' lengths are solved so that the *sphere* lands on the goal: every segment holds a roll
(±φmax on arcs, 0 on straights) and each roll change rolls the shell sideways by r·Δφ (eq. 1), which a
car does not do. The result is a list of (held roll, curvature, signed arc length) motions, the form the
search and its smoother use.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from planner.kinematics import arc_step, roll_shift, wrap

SAMPLE_M = 0.01  # spacing of the interpolated states the word is read from
MAX_SHOT_M = 10.0  # longer Reeds–Shepp shots are not tried (Nav2 Smac caps its analytic expansions too)
LAND_TOL_M = 1e-4  # the rolled end must land this close to the goal (and within 1e-4 rad of its heading)


@lru_cache(maxsize=8)
def _space(rho: float) -> Any:
    from ompl import base as ob

    return ob.ReedsSheppStateSpace(rho)


def car_word(start: tuple[float, float, float], goal: tuple[float, float, float], rho: float,
             max_length_m: float = math.inf) -> list[tuple[int, int, float]]:
    """The Reeds–Shepp path from ``start`` to ``goal`` as segments (turn −1/0/+1, direction ±1, length m);
    empty when it is longer than ``max_length_m``."""
    space = _space(rho)
    a, b, out = space.allocState(), space.allocState(), space.allocState()
    for state, pose in ((a, start), (b, goal)):
        state.setX(float(pose[0]))
        state.setY(float(pose[1]))
        yaw = wrap(float(pose[2]))
        state.setYaw(yaw if yaw < math.pi else -math.pi)  # OMPL's SO(2) is [−π, π)
    total = space.distance(a, b)
    if total < 1e-9 or total > max_length_m:
        return []
    n = max(8, math.ceil(total / SAMPLE_M))
    pts = np.empty((n + 1, 3))
    for i in range(n + 1):
        space.interpolate(a, b, i / n, out)
        pts[i] = out.getX(), out.getY(), out.getYaw()
    d = np.diff(pts[:, :2], axis=0)
    ds = np.hypot(d[:, 0], d[:, 1])
    heading = pts[:-1, 2]
    direction = np.where(d[:, 0] * np.cos(heading) + d[:, 1] * np.sin(heading) >= 0.0, 1, -1)
    dyaw = np.remainder(np.diff(pts[:, 2]) + math.pi, 2 * math.pi) - math.pi
    turning = np.abs(dyaw) > 0.5 * ds / rho
    turn = np.where(turning, np.sign(dyaw) * direction, 0).astype(int)
    segments: list[tuple[int, int, float]] = []
    for t, dr, step in zip(turn, direction, ds, strict=True):
        if segments and segments[-1][0] == t and segments[-1][1] == dr:
            segments[-1] = (t, dr, segments[-1][2] + float(step))
        else:
            segments.append((int(t), int(dr), float(step)))
    # a sample straddling a segment boundary can form a sliver of its own: fold it into its neighbour
    merged: list[tuple[int, int, float]] = []
    for seg in segments:
        if merged and seg[2] < 2.5 * SAMPLE_M:
            t, dr, length = merged[-1]
            merged[-1] = (t, dr, length + seg[2])
        else:
            merged.append(seg)
    return merged


def _roll(start: tuple[float, float, float, float], segs: list[tuple[float, float, float]], radius: float,
          end_roll: float) -> tuple[float, float, float]:
    """End pose of the sphere after the (held roll, curvature, signed length) motions, then ``end_roll``."""
    x, y, yaw, roll = start
    for held, curv, s in segs:
        x, y = roll_shift(x, y, yaw, radius, held - roll)
        x, y, yaw = arc_step(x, y, yaw, curv, s)
        roll = held
    x, y = roll_shift(x, y, yaw, radius, end_roll - roll)
    return x, y, yaw


def sphere_shot(
    start: tuple[float, float, float, float], goal: tuple[float, float, float], rho: float, max_roll: float,
    radius: float,
) -> list[tuple[float, float, float]] | None:
    """Motions (held roll, curvature, signed arc length) that roll the sphere from ``start`` (x, y, yaw, roll)
    along the Reeds–Shepp word towards ``goal`` and land on it upright, or None when the car's path is
    longer than :data:`MAX_SHOT_M` or the lengths cannot be solved (the sideways shifts of the roll changes
    do not fit the word's geometry)."""
    word = car_word(start[:3], goal, rho, MAX_SHOT_M)
    if not word:
        return None
    turns = [t for t, _, _ in word]
    dirs = [d for _, d, _ in word]

    def motions(lengths: np.ndarray) -> list[tuple[float, float, float]]:
        return [(t * max_roll, t / rho, d * float(abs(s))) for t, d, s in zip(turns, dirs, lengths, strict=True)]

    def residual(lengths: np.ndarray) -> np.ndarray:
        x, y, yaw = _roll(start, motions(lengths), radius, 0.0)
        return np.array([x - goal[0], y - goal[1], rho * wrap(yaw - goal[2])])

    guess = np.array([s for _, _, s in word])
    fit = least_squares(residual, guess, bounds=(0.0, np.inf), xtol=1e-12, ftol=1e-12, gtol=1e-12)
    err = residual(fit.x)
    if math.hypot(err[0], err[1]) > LAND_TOL_M or abs(err[2]) > LAND_TOL_M * rho:
        return None
    return [m for m in motions(fit.x) if abs(m[2]) > 1e-9]
